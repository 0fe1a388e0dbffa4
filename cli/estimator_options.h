// Command-line options shared by every subcommand that builds a regression estimator
// (ident fit, ident compare): --estimator, --dof, --delta, --forgetting, --stabilised,
// --nu0/--vy0/--vz0, --prior FILE.json, --exact, --lock-in-window, --lock-in-threshold, --no-lock-in-restart.
#pragma once

#include <optional>
#include <string>

#include <CLI/CLI.hpp>

#include "ident/regression/estimator_registry.h"

namespace ident::cli {

struct EstimatorCliOptions {
  std::string estimator = "rls";
  std::optional<double> dof;
  std::optional<int> delta;  // unset: 1 (refused by the estimators without the convention)
  double forgetting = 1.0;
  bool stabilised = false;
  std::optional<double> nu0, vy0, vz0;
  std::string prior_file;
  bool exact = false;
  std::optional<int> lock_in_window;
  std::optional<double> lock_in_threshold;
  bool no_lock_in_restart = false;

  // Adds the options to `app` (`with_estimator`: also --estimator).
  void AddTo(CLI::App& app, bool with_estimator = true);
  // Settings for `spec` (e.g. "student:3"; empty: this->estimator) and ρ parameters. With
  // `estimation_rows` > 0, a --lock-in-window longer than the estimation part (which the monitor could
  // never fill) is refused. Throws InvalidArgument / DataError (prior file) with one line naming the option.
  EstimatorSettings Resolve(int num_parameters, const std::string& spec = "", long estimation_rows = 0) const;
};

// Reads {"nu0": N, "V0": [[...], ...]} ((ρ+1)x(ρ+1), y first; no other keys). Throws DataError naming
// the file: "cannot read 'p.json': it is a directory", "p.json: unknown key "x" (known: nu0, V0)", ...
RegressionPrior ReadPriorJson(const std::string& path, int num_parameters);

// A data argument is a path, or the bare name of a bundled dataset ("dryer" → datasets/dryer.csv).
std::string ResolveDataPath(const std::string& name);

}  // namespace ident::cli
