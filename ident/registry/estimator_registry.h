// The one registry: every estimator and state observer by name, built from EstimatorSettings
// (estimator_settings.h) for a problem of its kind, behind the one interface AnyEstimator
// (common/estimator.h).
//
//   Regression estimators (RegressionProblem: ρ parameters; items (y, z)):
//   "rls"                     RecursiveLeastSquares
//   "cauchy"                  SafeStudentRegression with k = 1 (Kárný–Hangos; rejects dof ≠ 1)
//   "student" (needs dof)     SafeStudentRegression with k = dof ("student:3" or dof = 3)
//                             (exact = true: the plain StudentRegression recursion, no safeguards)
//   "huber"                   batch Huber M-estimation (IRLS, MAD scale; ident/regression/batch_regression.h)
//   "cauchy-ml"               batch Cauchy maximum likelihood in Θ and scale, global optimum from many starts
//   "lc:<noise>"              the log-concave Gaussian filter for y = z'θ + e, e of a log-concave density
//                             (ident/observers/lc_regression.h): lc:laplace, lc:huber[:k] (k = 1.345),
//                             lc:logistic, lc:gengauss:p (1 ≤ p ≤ 2), lc:gaussian (= RLS)
//   State observers (ObserverProblem, observer_registry.h; items (u(k−1), y(k))):
//   "kalman", "lc_gaussian", "lc_truncated", "grid"
//   (further regression estimators are registered with RegisterRegressionEstimator)
//
// Example:
//   auto est = ident::MakeEstimator(ident::ParseEstimatorSpec("student:3"), ident::RegressionProblem{4});
//   auto obs = ident::MakeEstimator(ident::ParseEstimatorSpec("grid:points=64"), observer_problem);
//   est->Update(ident::RegressionItem{y, z});  obs->Update(ident::StateSpaceItem{u, y});
//   The typed forms: MakeRegressionEstimator(settings, ρ) and MakeStateObserver(settings, problem).
#pragma once

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "common/estimator.h"
#include "ident/registry/estimator_settings.h"
#include "ident/registry/observer_registry.h"
#include "ident/regression/regression_estimator.h"

namespace ident {

// What a regression estimator needs besides its settings: the number of parameters ρ.
struct RegressionProblem {
  int num_parameters = 0;
};

// Builds the estimator `settings.name` for `problem`; throws InvalidArgument naming the option for an
// unknown name, a bad option, or a problem of the other kind ("'kalman' is a state observer: …").
std::unique_ptr<AnyEstimator> MakeEstimator(const EstimatorSettings& settings, const RegressionProblem& problem);
std::unique_ptr<AnyEstimator> MakeEstimator(const EstimatorSettings& settings, const ObserverProblem& problem);

// Every registered name, the regression estimators first, in the order they are documented.
std::vector<std::string> EstimatorNames();
// The kind of item the estimator `name` takes; throws InvalidArgument for an unknown name.
ItemKind EstimatorItemKind(std::string_view name);

// The typed form for regressions: builds the estimator; throws InvalidArgument naming the option for an
// unknown name or bad option.
std::unique_ptr<AnyRegressionEstimator> MakeRegressionEstimator(const EstimatorSettings& settings, int num_parameters);

// The registered regression estimators' names, in the order they are documented.
std::vector<std::string> RegressionEstimatorNames();

// What a workflow needs to know of a registered estimator before it builds one.
struct EstimatorTraits {
  // Its default prior is flat with the data's own scale, RegressionPrior::Flat(mean squares of the
  // regressors) (RLS), or — the Kárný–Hangos estimators, whose robust start is scale-invariant — the
  // provisional prior of its start-up is (DataScaledProvisionalV0); the batch ones have none.
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

// Adds an estimator under `name` (after the built-in ones): MakeEstimator, MakeRegressionEstimator,
// EstimatorNames, the workflow and the command line's --estimator then know it. The usual one is the
// LD-form shell with a weight rule of one's own (ident/regression/weighted_regression.h), e.g.
//   RegisterRegressionEstimator("huber-weight", [](const EstimatorSettings& s, int rho) {
//     return std::make_unique<RegressionEstimatorModel<BasicWeightedRegression<MyRule>>>(
//         "huber-weight", rho, RlsOptions{s.forgetting, s.prior});
//   });
// A regression estimator takes the typed settings only: the registry refuses any other option of its spec.
// Throws InvalidArgument for an empty name, one with ':', ',' or a space, a taken name (an observer's
// too) or no factory. Register before building estimators, from one thread (the registry is not locked).
void RegisterRegressionEstimator(const std::string& name, RegressionEstimatorFactory factory,
                                 EstimatorTraits traits = {});

// The default prior in the data's own scale for `settings` — set when the estimator has one
// (EstimatorTraits::data_scaled_prior), the settings leave the prior to it (no prior, not exact), and every
// mean square is in [1e-280, 1e280]; otherwise empty (the estimator's absolute default, whose checks then
// name a problem of scale).
std::optional<RegressionPrior> DataScaledDefaultPrior(const EstimatorSettings& settings,
                                                      const Eigen::VectorXd& mean_squares);
// Puts the default prior of `settings` in the data's own scale (mean squares of y and of each regressor
// over the estimation data): the flat prior of DataScaledDefaultPrior, or for a Kárný–Hangos estimator
// (EstimatorTraits::lock_in) the provisional V(0) of its start-up (DataScaledProvisionalV0), which leaves
// its robust start as it is. False (settings unchanged) where DataScaledDefaultPrior would be empty.
bool UseDataScaledPrior(EstimatorSettings& settings, const Eigen::VectorXd& mean_squares);

}  // namespace ident
