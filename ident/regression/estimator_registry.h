// Run-time selection of regression estimators by name.
//
//   "rls"                     RecursiveLeastSquares
//   "cauchy"                  SafeStudentRegression with k = 1 (Kárný–Hangos; rejects dof ≠ 1)
//   "student" (needs dof)     SafeStudentRegression with k = dof ("student:3" or dof = 3)
//                             (exact = true: the plain StudentRegression recursion, no safeguards)
//   "huber"                   batch Huber M-estimation (IRLS, MAD scale; ident/regression/batch_regression.h)
//   "cauchy-ml"               batch Cauchy maximum likelihood in Θ and scale, global optimum from many starts
//   "lc:<noise>"              the log-concave Gaussian filter for y = z'θ + e, e of a log-concave density
//                             (ident/regression/lc_regression.h): lc:laplace, lc:huber[:k] (k = 1.345),
//                             lc:logistic, lc:gengauss:p (1 ≤ p ≤ 2), lc:gaussian (= RLS)
//   (further names are registered in estimator_registry.cc as estimators are added)
//
// Example:
//   ident::EstimatorSettings s = ident::ParseEstimatorSpec("rls");
//   s.forgetting.factor = 0.99;
//   auto est = ident::MakeRegressionEstimator(s, /*num_parameters=*/4);   // throws on bad options
#pragma once

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "ident/regression/forgetting.h"
#include "ident/regression/regression_estimator.h"
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
  std::optional<double> dof;             // Student-t degrees of freedom k
  std::string noise;                     // "lc": the noise law ("laplace", "huber:1.345", …)
  std::optional<int> delta;              // ω-exponent convention δ ∈ {0, 1} (Kárný–Hangos; unset: 1)
  bool exact = false;                    // switch off every safeguard beyond the spec's recursion
  LockInSettings lock_in;                // refused (if any() is set) for "rls" and together with `exact`
};

// Parses "name" or "name:value" / "name:k=value" (e.g. "student:3", "student:k=3") into
// settings.name and settings.dof, and "lc:<noise>" (e.g. "lc:huber:1.345") into name "lc" and settings.noise.
// Throws InvalidArgument for a malformed spec.
EstimatorSettings ParseEstimatorSpec(std::string_view spec, EstimatorSettings base = {});

// Builds the estimator; throws InvalidArgument naming the option for an unknown name or bad option.
std::unique_ptr<AnyRegressionEstimator> MakeRegressionEstimator(const EstimatorSettings& settings, int num_parameters);

// The registered names, in the order they are documented.
std::vector<std::string> RegressionEstimatorNames();

// What a workflow needs to know of a registered estimator before it builds one.
struct EstimatorTraits {
  // Its default prior is flat with the data's own scale, RegressionPrior::Flat(mean squares of the
  // regressors) (RLS); the Kárný–Hangos start-up prior is scale-invariant already, the batch ones have none.
  bool data_scaled_prior = false;
  // It has the lock-in safeguard and the ω-exponent convention δ (the Kárný–Hangos estimators).
  bool lock_in = false;
  // It models outliers (a heavy-tailed or robust criterion): the workflow detrends its output robustly
  // (workflow/fit.h FitOptions::robust_offset). A least-squares estimator keeps the plain mean.
  bool robust = false;
};
// Throws InvalidArgument for an unknown name.
EstimatorTraits RegressionEstimatorTraits(std::string_view name);

// Builds an estimator from settings for ρ parameters; throws InvalidArgument naming a bad option.
using RegressionEstimatorFactory =
    std::function<std::unique_ptr<AnyRegressionEstimator>(const EstimatorSettings&, int num_parameters)>;

// Adds an estimator under `name` (after the built-in ones): MakeRegressionEstimator, RegressionEstimatorNames,
// the workflow and the command line's --estimator then know it. The usual one is the LD-form shell with a
// weight rule of one's own (ident/regression/weighted_regression.h), e.g.
//   RegisterRegressionEstimator("huber-weight", [](const EstimatorSettings& s, int rho) {
//     return std::make_unique<RegressionEstimatorModel<BasicWeightedRegression<MyRule>>>(
//         "huber-weight", rho, RlsOptions{s.forgetting, s.prior});
//   });
// Throws InvalidArgument for an empty name, one with ':', ',' or a space, a taken name or no factory.
// Register before building estimators, from one thread (the registry is not locked).
void RegisterRegressionEstimator(const std::string& name, RegressionEstimatorFactory factory,
                                 EstimatorTraits traits = {});

// The default prior in the data's own scale for `settings` — set when the estimator has one
// (EstimatorTraits::data_scaled_prior), the settings leave the prior to it (no prior, not exact), and every
// mean square is in [1e-280, 1e280]; otherwise empty (the estimator's absolute default, whose checks then
// name a problem of scale).
std::optional<RegressionPrior> DataScaledDefaultPrior(const EstimatorSettings& settings,
                                                      const Eigen::VectorXd& mean_squares);

}  // namespace ident
