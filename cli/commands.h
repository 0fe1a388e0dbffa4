// The subcommands of the `ident` program. Each AddXCommand adds one subcommand with its options and
// a callback; the callback throws ident::InvalidArgument / ident::DataError for bad options or data
// (main prints one line and exits 1). CLI11 parse errors exit 2.
#pragma once

#include <CLI/CLI.hpp>

namespace ident::cli {

void AddFitCommand(CLI::App& app);         // ident fit        (fit_command.cc)
void AddDatasetsCommand(CLI::App& app);    // ident datasets   (datasets_command.cc)
void AddCompareCommand(CLI::App& app);     // ident compare    (compare_command.cc)
void AddMemsCommand(CLI::App& app);        // ident mems       (mems_command.cc)
void AddLogcondensCommand(CLI::App& app);  // ident logcondens (logcondens_command.cc)
void AddSmoothCommand(CLI::App& app);      // ident smooth     (smooth_command.cc)
void AddOrdersCommand(CLI::App& app);      // ident orders     (orders_command.cc)
void AddPredictCommand(CLI::App& app);     // ident predict    (predict_command.cc)
void AddStreamCommand(CLI::App& app);      // ident stream     (stream_command.cc)

// Exit codes of every subcommand.
inline constexpr int kExitOk = 0;
inline constexpr int kExitBadInput = 1;  // bad data or options: one line on stderr
inline constexpr int kExitUsage = 2;     // command-line usage error

}  // namespace ident::cli
