// Reading recorded data from MATLAB .mat files (v5, v7 and v7.3) through libmatio.
//
// Every real numeric variable (double, single, integer, logical) that is a vector becomes a column named
// after it; a matrix of N rows and M > 1 columns becomes the columns NAME_1 … NAME_M (a row of length N,
// 1×N, is a vector too). The record has as many rows as its longest variable; scalars (1×1: a sample
// time, a gain) are passed over when the record is longer, as are text, cell, struct and empty variables.
// The columns come in the order libmatio lists the variables: as stored (v5, v7), by name (v7.3).
// With CsvOptions::missing_as_nan NaN/Inf values are missing samples; without, they are refused. Problems
// are ident::DataError with one line naming the file and the variable:
//   cannot open 'x.mat' as a MATLAB file (v5, v7 or v7.3)
//   x.mat: variable 'u' has 999 samples; 'y' has 1000
//   x.mat: variable 'z' has 3 dimensions; columns are vectors or matrices
//   x.mat: variable 'c' is complex
//   x.mat: variable 'y', row 17: NaN is not a finite number (pass --missing ...)
//   x.mat: no numeric variable
//   x.mat: this build reads no .mat files (libmatio was not found when it was built)
// Example:
//   ident::io::DataTable t = ident::io::ReadDataFile("record.mat");   // or a CSV file
#pragma once

#include <string>

#include "ident/io/csv.h"

namespace ident::io {

// True if the name ends in ".mat" (any case).
bool IsMatFile(const std::string& path);

// Reads a .mat file as described above. Throws DataError.
DataTable ReadMat(const std::string& path, const CsvOptions& options = {});

// ReadMat for a .mat file, ReadCsv otherwise.
DataTable ReadDataFile(const std::string& path, const CsvOptions& options = {});

// True if this build reads .mat files.
bool MatFilesSupported();

}  // namespace ident::io
