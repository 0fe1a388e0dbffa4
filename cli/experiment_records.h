// The records of a command that reads one experiment or several (ident fit, compare, orders, predict):
// DATA given once or once per experiment, and --experiment-column NAME (ident/workflow/experiments.h).
// Several experiments are read into one table in memory whose regressors restart at each experiment.
#pragma once

#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "ident/io/csv.h"
#include "ident/workflow/experiments.h"

namespace ident::cli {

// Adds --experiment-column to `app`, parsed into `column`.
void AddExperimentColumnOption(CLI::App& app, std::string& column);
// Adds the DATA positional (one file or bundled dataset name, or several: one experiment each), described
// by `what` ("CSV file with a header" by default), and --experiment-column.
void AddDataFilesOptions(CLI::App& app, std::vector<std::string>& data, std::string& experiment_column,
                         const std::string& what = "CSV file with a header, or a bundled dataset's name (e.g. dryer)");
// Adds --missing (empty/NaN/Inf cells are missing samples; time-column gaps are filled with them).
void AddMissingOption(CLI::App& app, bool& missing);
// With more than one experiment, prints "N experiments (regressors restart at each): name rows A-B, …"
// (1-based rows) without a line end; nothing for one.
void PrintExperiments(const std::vector<workflow::Experiment>& experiments);

struct ExperimentFile {
  std::string path;
  long rows = 0;
  std::string checksum;  // workflow::Checksum of its bytes as read; empty: not taken while reading
};

struct ExperimentRecords {
  io::DataTable table;
  std::vector<workflow::Experiment> experiments;  // one ("1", the whole table) for one record
  std::vector<ExperimentFile> files;              // in the order given
  bool several = false;                           // several files or an experiment column
  std::string name;                               // the path, or "a.csv + b.csv"
};

// Reads the (resolved) `paths` by io::ReadDataFile: one file as it is, several files (or any with an
// experiment `column`) by workflow::ConcatenateExperiments. Throws DataError as they do.
ExperimentRecords ReadExperimentRecords(const std::vector<std::string>& paths, const std::string& column,
                                        const io::CsvOptions& csv);

}  // namespace ident::cli
