// The one options mechanism of the estimator registry (estimator_registry.h): the settings every
// estimator and observer is built from, and the spec text that names one.
//
// A spec is "name", "name:value" or "name:key=value,key=value":
//   "rls", "cauchy", "student:3" (= student:k=3 = student:dof=3), "lc:huber:1.345" (the noise law follows
//   "lc:"), "rls:forgetting=0.99", "grid:points=64x48,noise_sigmas=5"
// The keys every recursive regression estimator knows are read into their typed fields at parsing:
//   k, dof           Student-t degrees of freedom                 → dof
//   forgetting       exponential forgetting factor λ ∈ (0, 1]     → forgetting.factor
//   delta            Kárný–Hangos ω-exponent convention (0 or 1)  → delta
//   lock_in_window, lock_in_threshold                            → lock_in
// Any other key stays in `options` for the estimator that owns it (the grid observer's points, …); an
// estimator refuses, naming it, every option and every typed field that does not apply to it.
//
// Example:
//   ident::EstimatorSettings s = ident::ParseEstimatorSpec("student:3");
//   s.forgetting.factor = 0.99;                // the command line's --forgetting
#pragma once

#include <map>
#include <optional>
#include <string>
#include <string_view>

#include "ident/regression/forgetting.h"
#include "ident/regression/regression_prior.h"

namespace ident {

// The lock-in safeguard of the robust estimators (ident/regression/safe_student_regression.h); unset = its defaults
// (window max(100, 20ρ), threshold 0.3, restart on).
struct LockInSettings {
  std::optional<int> window;        // M in 2..1000000 (kMaxLockInWindow; 0 = automatic)
  std::optional<double> threshold;  // 0 < threshold < (k+1)/k
  bool restart = true;              // false: flag lock-ins only, never restart
  std::optional<long> history;      // samples kept for restarts to replay (0 = all; SafeStudentOptions::history_limit)
  bool any() const { return window || threshold || !restart || history; }
};

// Options common to the command line and the registry; each estimator reads those it knows and
// rejects ones that make no sense for it, naming the option.
struct EstimatorSettings {
  std::string name = "rls";
  ForgettingOptions forgetting;
  std::optional<RegressionPrior> prior;  // explicit (ν(0), V(0)); otherwise the estimator's default
  // cauchy/student without `prior`: V(0) of the start-up's provisional estimate (SafeStudentOptions)
  std::optional<Eigen::MatrixXd> provisional_v0;
  std::optional<double> dof;                   // Student-t degrees of freedom k
  std::string noise;                           // "lc": the noise law ("laplace", "huber:1.345", …)
  std::optional<int> delta;                    // ω-exponent convention δ ∈ {0, 1} (Kárný–Hangos; unset: 1)
  bool exact = false;                          // switch off every safeguard beyond the spec's recursion
  LockInSettings lock_in;                      // refused (if any() is set) for "rls" and together with `exact`
  std::map<std::string, std::string> options;  // the estimator's own options, key → value (text)

  // The first typed field that differs from its default, by its spec key ("dof", "forgetting", …), or empty:
  // what an estimator that takes none of them (an observer) refuses, named.
  std::string first_regression_setting() const;
};

// Parses a spec (above) into `base`'s name, typed fields and options. Throws InvalidArgument for a
// malformed spec, a key given twice or a typed key whose value is not a number.
EstimatorSettings ParseEstimatorSpec(std::string_view spec, EstimatorSettings base = {});

// Reads the text of option `key` of estimator `name` as a finite number / an integer; throws InvalidArgument
// naming the estimator, the key and the text otherwise.
double ParseOptionNumber(std::string_view name, std::string_view key, std::string_view text);
int ParseOptionInteger(std::string_view name, std::string_view key, std::string_view text);

}  // namespace ident
