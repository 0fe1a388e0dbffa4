// The --delimiter option of every subcommand that reads a data file (ident/io/csv.h): ',', ';', tab,
// space (runs of spaces and tabs) or auto (detected from the header and the first data line).
#pragma once

#include <CLI/CLI.hpp>

#include "ident/io/csv.h"

namespace ident::cli {

// Adds --delimiter to `app`, parsed into csv.delimiter.
void AddDelimiterOption(CLI::App& app, io::CsvOptions& csv);

}  // namespace ident::cli
