// The LD-form regression shell and its extension point, the weight rule.
//
// BasicWeightedRegression<Rule, ρ> keeps the normalised statistics (ν, V = L'DL) of [y; z] and takes each
// sample with the guarded step of ident/regression/internal/step_driver.h — validate, forget, innovation,
// weight, plan, check, commit or roll back — as V(t) = (1 − β)Ṽ + β h h', ν(t) = ν̃ + 1 [spec §3, §6],
// O(ρ²) per update, noexcept and allocation-free. The weight β(t) ∈ (0, 1) comes from the rule:
//
//   struct MyRule {
//     static constexpr bool kNeedsXi = true;  // the rule reads in.xi, in.xi_z (one more back substitution)
//     // optional, for a rule of ν alone (in all NaN): β first, then innovation and update in one sweep
//     static constexpr bool kNeedsInnovation = false;
//     double operator()(double nu, const Innovation& in) const noexcept;  // β ∈ (0, 1); else the step is refused
//   };
//
// with Innovation (ident/regression/internal/extended_information.h): ξ = 1 − h'Ṽ⁻¹h, ξ_z = 1 − z'Ṽ_z⁻¹z
// and the prediction error ê = y − Θ̂'z against the statistics before the sample; ν·β is the sample's
// weight relative to least squares (ident/regression/outlier_decision.h) and u = ξ_z − ξ its squared
// prediction error in units of the current residual scale [spec §3]. LeastSquaresWeight (β = 1/ν [spec §7c])
// makes recursive least squares (ident/regression/rls.h). A rule is registered by name with
// RegisterRegressionEstimator (ident/registry/estimator_registry.h); the Kárný–Hangos estimators take the
// same step with their own weighting-polynomial rule and their start-up and lock-in machinery around it
// (ident/regression/student_regression.h).
#pragma once

#include <cmath>
#include <limits>
#include <optional>
#include <string>
#include <utility>

#include <Eigen/Core>

#include "common/error.h"
#include "common/step_report.h"
#include "ident/linalg/ld_factor.h"
#include "ident/regression/forgetting.h"
#include "ident/regression/internal/extended_information.h"
#include "ident/regression/internal/step_driver.h"
#include "ident/regression/regression_prior.h"

namespace ident {

// The shell's options (named for its best-known instance).
struct RlsOptions {
  ForgettingOptions forgetting;
  // (ν(0), V(0)); defaults to RegressionPrior::Flat(ρ), which reproduces batch least squares.
  std::optional<RegressionPrior> prior;

  // "" if valid for ρ parameters, else one line naming the option.
  std::string Validate(int num_parameters) const;
};

// β = 1/ν: every sample weighs the same, recursive least squares [spec §7c].
struct LeastSquaresWeight {
  static constexpr bool kNeedsXi = false;
  static constexpr bool kNeedsInnovation = false;  // β from ν alone: taken before the innovation (one sweep)
  double operator()(double nu, const Innovation&) const noexcept {
    if (!(nu == nu_)) nu_ = nu, beta_ = 1 / nu;  // ν(t) settles under forgetting: then no division
    return beta_;
  }

 private:
  mutable double nu_ = std::numeric_limits<double>::quiet_NaN(), beta_ = std::numeric_limits<double>::quiet_NaN();
};

template <class Rule, int Rho = Eigen::Dynamic>
class BasicWeightedRegression {
  static constexpr int kDim = Rho == Eigen::Dynamic ? Eigen::Dynamic : Rho + 1;

 public:
  using ParamVector = typename ExtendedInformation<kDim>::ParamVector;

  // Throws InvalidArgument naming the option if `options` is invalid.
  explicit BasicWeightedRegression(int num_parameters, const RlsOptions& options = {}, Rule rule = {})
      : options_(Checked(num_parameters, options)),
        prior_(options_.prior ? *options_.prior : RegressionPrior::Flat(num_parameters)),
        stats_(prior_),
        prior_factor_(prior_.V0),
        rule_(std::move(rule)) {}

  // One sample. Rejects (state unchanged) a sample with a non-finite entry, a regressor of the
  // wrong size, or one so large that the update would overflow (kRejectedInvalid). While disabled:
  // kSkipped, state unchanged (the sample is not even inspected).
  // Safeguards (ident/regression/internal/step_driver.h; O(ρ) checks in the common case, allocation-free):
  //   windup  exponential forgetting without excitation shrinks d geometrically (d ∝ λ^t) until it
  //           underflows; a step that would leave some d_i below kWindupFloor is taken without
  //           forgetting (λ = 1 for this step: d then shrinks only as ν/(ν+1)), so the estimator
  //           neither underflows nor freezes, and recovers as soon as excitation returns;
  //   health  a step whose result would have some d_i not a positive normal number, or L, Θ̂ not
  //           finite (overflow on samples of wildly mixed scales) is undone: kNumericalFailure.
  template <class Derived>
  StepReport Update(double y, const Eigen::MatrixBase<Derived>& z) noexcept {
    if (!enabled_) return {StepStatus::kSkipped};
    const DrivenStep s = driver_.template Run<Rule::kNeedsXi, !NeedsInnovation()>(
        stats_, {options_.forgetting.factor, options_.forgetting.stabilised, kWindupFloor}, prior_.nu0, prior_factor_,
        y, z, rule_);
    if (s.report.updated()) samples_ = s.lambda * samples_ + 1;
    // Built from the fields, not copied whole: see StepDriver::Run.
    return {s.report.status, s.report.weight, s.report.nu, s.report.prediction_error};
  }

  // Below this, d is taken to be winding up under forgetting (see Update); 2^-900 ≈ 1.2e-271.
  static constexpr double kWindupFloor = 0x1p-900;

  int num_parameters() const { return stats_.num_parameters(); }
  const ParamVector& parameters() const { return stats_.parameters(); }
  template <class Derived>
  double Predict(const Eigen::MatrixBase<Derived>& z) const {
    return stats_.Predict(z);
  }
  double nu() const { return stats_.nu(); }
  double Dy() const { return stats_.Dy(); }
  // Discounted number of samples n = Σ λ^k.
  double samples() const { return samples_; }
  // s² = ν D_y/(n − ρ); NaN until n > ρ. For least squares the residual variance; for another rule the
  // weighted one, and covariance() below the one-sided posterior's, not a calibrated (sandwich) covariance.
  double noise_variance() const {
    const double dof = samples_ - num_parameters();
    return dof > 0 ? stats_.nu() * stats_.Dy() / dof : std::numeric_limits<double>::quiet_NaN();
  }
  double noise_std() const { return std::sqrt(noise_variance()); }
  // Cov(Θ̂) = s² (νV_z)⁻¹ (allocates, O(ρ³)).
  Eigen::MatrixXd covariance() const { return noise_variance() / stats_.nu() * stats_.VzInverse(); }
  // The same Cov(Θ̂) into a caller-owned ρ x ρ matrix, without allocating (NaN until n > ρ).
  // Throws InvalidArgument only if `out` has the wrong size.
  void CovarianceInto(Eigen::Ref<Eigen::MatrixXd> out) const {
    IDENT_REQUIRE(out.rows() == num_parameters() && out.cols() == num_parameters(),
                  "covariance output is {}x{}; need {}x{}", out.rows(), out.cols(), num_parameters(), num_parameters());
    stats_.ScaledVzInverse(noise_variance() / stats_.nu(), out);
  }
  const ExtendedInformation<kDim>& statistics() const { return stats_; }
  const RlsOptions& options() const { return options_; }
  const Rule& rule() const { return rule_; }

  // A missing sample (no measurement this period): returns kSkipped; the state is untouched, so
  // the next Update() continues exactly as if this period had not happened.
  StepReport Skip() const noexcept { return {StepStatus::kSkipped}; }
  // Enable flag (MATLAB's EnableAdapt): while false, Update() skips every sample. Read-outs and
  // Predict() keep working on the frozen state.
  void set_enabled(bool enabled) noexcept { enabled_ = enabled; }
  bool enabled() const noexcept { return enabled_; }

  // Back to the prior (ν0, V0) and n = 0, from a factor kept since construction: no allocation.
  // Keeps the enable flag and the current forgetting factor.
  void Reset() noexcept {
    stats_.Reset(prior_.nu0, prior_factor_);
    samples_ = 0;
  }
  const RegressionPrior& prior() const { return prior_; }
  // Changes λ on the fly (the next update uses it). Throws InvalidArgument if λ ∉ (0, 1]; no
  // allocation otherwise.
  void set_forgetting(double lambda) {
    ForgettingOptions f = options_.forgetting;
    f.factor = lambda;
    const std::string error = f.Validate();
    IDENT_REQUIRE(error.empty(), "{}", error);
    options_.forgetting = f;
  }

 private:
  // Whether the rule reads its Innovation argument: yes unless it declares kNeedsInnovation = false.
  static constexpr bool NeedsInnovation() {
    if constexpr (requires { Rule::kNeedsInnovation; })
      return Rule::kNeedsInnovation || Rule::kNeedsXi;
    else
      return true;
  }
  static const RlsOptions& Checked(int num_parameters, const RlsOptions& options) {
    const std::string error = options.Validate(num_parameters);
    IDENT_REQUIRE(error.empty(), "{}", error);
    return options;
  }

  RlsOptions options_;
  RegressionPrior prior_;
  ExtendedInformation<kDim> stats_;
  StepDriver<kDim> driver_{stats_};
  LdFactor<kDim> prior_factor_;
  Rule rule_;
  double samples_ = 0;
  bool enabled_ = true;
};

}  // namespace ident
