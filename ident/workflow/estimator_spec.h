// The estimator of a fit, as a user states it: a registered name (ident/registry/estimator_registry.h)
// and the options every estimator or some of them take. The command line (`--estimator`, `--dof`,
// `--forgetting`, …) and the Python package fill the same fields; Resolve() checks them together and
// turns them into EstimatorSettings.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "ident/registry/estimator_registry.h"

namespace ident::workflow {

struct EstimatorSpec {
  std::string estimator = "rls";  // "rls", "cauchy", "student:3", "huber", "cauchy-ml", …
  std::optional<double> dof;      // Student-t degrees of freedom k
  std::optional<int> delta;       // unset: 1 (refused by the estimators without the convention)
  double forgetting = 1.0;
  bool stabilised = false;
  std::optional<double> nu0, vy0, vz0;   // prior V(0) = diag(vy0, vz0·I), ν(0) = nu0 (all three or none)
  std::string prior_file;                // prior as JSON {"nu0": N, "V0": [[...]]}
  std::optional<RegressionPrior> prior;  // an explicit prior (excludes nu0/vy0/vz0 and prior_file)
  bool exact = false;
  std::optional<int> lock_in_window;
  std::optional<double> lock_in_threshold;
  bool no_lock_in_restart = false;
  std::optional<long> history_limit;  // samples the robust estimators keep for restarts (0 = all)

  // Settings for `name` (e.g. "student:3"; empty: this->estimator) and ρ parameters. With
  // `estimation_rows` > 0, a lock-in window longer than the estimation part (which the monitor could
  // never fill) is refused. Throws InvalidArgument / DataError (prior file) with one line naming the option.
  EstimatorSettings Resolve(int num_parameters, const std::string& name = "", long estimation_rows = 0) const;
  // Settings for several estimators compared on one record: as Resolve, with the lock-in options and δ
  // kept only for the estimators that have them (the Kárný–Hangos ones).
  std::vector<EstimatorSettings> ResolveAll(int num_parameters, const std::vector<std::string>& names,
                                            long estimation_rows) const;
};

// Splits comma-separated estimator lists ("rls,cauchy") into names. Throws InvalidArgument naming
// --estimators for an empty name (as in "rls,,cauchy").
std::vector<std::string> SplitEstimatorLists(const std::vector<std::string>& lists);

// Reads {"nu0": N, "V0": [[...], ...]} ((ρ+1)x(ρ+1), y first; no other keys). Throws DataError naming
// the file: "cannot read 'p.json': it is a directory", "p.json: unknown key "x" (known: nu0, V0)", ...
RegressionPrior ReadPriorJson(const std::string& path, int num_parameters);

}  // namespace ident::workflow
