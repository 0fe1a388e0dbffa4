// ScanCsvFirstPass of ident/workflow/fit.h with its limits as parameters, so that tests can make a small file
// take each of its paths (internal to ident/workflow/).
#pragma once

#include <optional>
#include <string>

#include "ident/io/csv.h"
#include "ident/workflow/data_source.h"
#include "ident/workflow/fit.h"

namespace ident::workflow::internal {

struct FirstPassLimits {
  long min_margin_rows = 4096;     // the margin before split·size, in rows: at least this many,
  double margin_fraction = 0.002;  // and at least this fraction of the rows the file probably has (negative: that
                                   // many rows past the guess instead, to test the rows held)
  long held_values = 1L << 18;     // at most this many values held (rows × columns)
};

std::optional<CsvFirstPass> ScanCsvFirstPass(const std::string& path, const io::CsvOptions& csv, DataSource& source,
                                             const FitOptions& options, bool mean_squares,
                                             const FirstPassLimits& limits);

}  // namespace ident::workflow::internal
