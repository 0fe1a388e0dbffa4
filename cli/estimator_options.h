// Command-line options shared by every subcommand that builds a regression estimator
// (ident fit, ident compare): --estimator, --dof, --delta, --forgetting, --stabilised,
// --nu0/--vy0/--vz0, --prior FILE.json, --exact, --lock-in-window, --lock-in-threshold, --no-lock-in-restart,
// --history-limit.
#pragma once

#include <optional>
#include <string>

#include <CLI/CLI.hpp>

#include "ident/workflow/estimator_spec.h"

namespace ident::cli {

// The fields and their meaning are workflow::EstimatorSpec's; this adds the command line.
struct EstimatorCliOptions : workflow::EstimatorSpec {
  // Adds the options to `app` (`with_estimator`: also --estimator).
  void AddTo(CLI::App& app, bool with_estimator = true);
};

using workflow::ReadPriorJson;

// A data argument is a path, or the bare name of a bundled dataset ("dryer" → datasets/dryer.csv).
std::string ResolveDataPath(const std::string& name);

}  // namespace ident::cli
