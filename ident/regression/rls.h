// Recursive least squares on the LD-factorised extended information matrix (normalised RLS).
//
//   Model:  y(t) = Θ'z(t) + e(t),  e Gaussian.
//   Step:   ν(t) = λν(t−1) + 1,  β(t) = 1/ν(t),  V(t) = (1−β)Ṽ + β h h',  h = [y; z]   [spec §7c, eq. (55)]
//           (the unnormalised information ν(t)V(t) = λ ν(t−1)V(t−1) + h h'); stabilised forgetting
//           as in spec §7b.
//   Read-outs: Θ̂ = V_z⁻¹V_zy; residual sum ν D_y; noise variance s² = ν D_y/(n − ρ) with
//           n = Σ λ^k the (discounted) sample count; Cov(Θ̂) = s² (ν V_z)⁻¹ = D_y V_z⁻¹/(n − ρ).
//
// Cost per Update() (m = ρ+1; one flop = one add, multiply, divide or square root; counted from the
// loops in ident/regression/internal/step_driver.h, step_guard.h, extended_information.h and ld_factor.h):
//   input check |h|² = y² + |z|², |h|               2ρ + 2
//   ν̃ = λν, ν = ν̃ + 1, β = 1/ν, n ← λn + 1          5
//   back substitution L'g = h, ê = g_0               m(m−1)          [spec §6]
//   plan: new d, b_j (prefix-sum form), Σd, Σ|g|     12m + 2         (O(m): ld_factor.h PlanUpdate)
//   guard verdict (bound on max|L|, Θ̂)              5               (step_guard.h; no copy)
//   rank-one update of L (Agee–Turner), bound        2m(m−1) + 5     [spec §6]
//   total, exponential forgetting                    3m² + 9m + 2ρ + 19 = 3ρ² + 17ρ + 31
//                                                    (ρ = 4: 147 flops, plus ≈ 4m comparisons)
//   stabilised forgetting adds a copy of L, d and m  ≈ (2/3)m³ + 4m²   (O(ρ³); ρ = 4: ≈ 190 more)
//   sparse rank-one updates with the rows of L_a [spec §7b]
//   a step the O(m) guard cannot prove healthy       + a copy of L, d and Σ|L| (O(m²); rare: extreme scales)
//   parameters() after an update (cached)            ρ²     (forward substitution)
//   CovarianceInto()                                 ≈ (5/6)ρ³ + O(ρ²)
// No step allocates after construction (fixed-size and dynamic variants alike).
//
// Real-time loop features (what MATLAB's recursive estimators offer; all allocation-free; Update, Skip,
// Reset and set_enabled are noexcept, set_forgetting and CovarianceInto throw only on invalid arguments):
//   set_enabled(false)      Update() returns kSkipped and leaves the state bit-identical (EnableAdapt)
//   Skip()                  a missing sample: kSkipped, state untouched
//   Reset()                 back to the prior (ν0, V0)
//   set_forgetting(λ)       takes effect at the next update (throws only for λ ∉ (0, 1])
//   CovarianceInto(P)       Cov(Θ̂) into a caller-owned ρ x ρ matrix, at any time
//
// Example:
//   ident::BasicRecursiveLeastSquares<4> rls(/*num_parameters=*/4, {.forgetting = {.factor = 0.99}});
//   Eigen::Matrix4d P;
//   for (...) {
//     rls.set_enabled(excitation_ok);
//     ident::StepReport r = sensor_ok ? rls.Update(y, z) : rls.Skip();
//     rls.CovarianceInto(P);
//   }
//   Eigen::Vector4d theta = rls.parameters();
#pragma once

#include <cmath>
#include <limits>
#include <optional>
#include <string>

#include <Eigen/Core>

#include "common/error.h"
#include "common/step_report.h"
#include "ident/regression/forgetting.h"
#include "ident/regression/internal/extended_information.h"
#include "ident/regression/internal/step_driver.h"
#include "ident/regression/regression_prior.h"

namespace ident {

struct RlsOptions {
  ForgettingOptions forgetting;
  // (ν(0), V(0)); defaults to RegressionPrior::Flat(ρ), which reproduces batch least squares.
  std::optional<RegressionPrior> prior;

  // "" if valid for ρ parameters, else one line naming the option.
  std::string Validate(int num_parameters) const;
};

template <int Rho = Eigen::Dynamic>
class BasicRecursiveLeastSquares {
  static constexpr int kDim = Rho == Eigen::Dynamic ? Eigen::Dynamic : Rho + 1;

 public:
  using ParamVector = typename ExtendedInformation<kDim>::ParamVector;

  // Throws InvalidArgument naming the option if `options` is invalid.
  explicit BasicRecursiveLeastSquares(int num_parameters, const RlsOptions& options = {})
      : options_(Checked(num_parameters, options)),
        prior_(options_.prior ? *options_.prior : RegressionPrior::Flat(num_parameters)),
        stats_(prior_),
        prior_factor_(prior_.V0) {}

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
    const DrivenStep s = driver_.template Run</*WithXi=*/false>(
        stats_, {options_.forgetting.factor, options_.forgetting.stabilised, kWindupFloor}, prior_.nu0, prior_factor_,
        y, z, [](double nu, const Innovation&) { return 1 / nu; });  // β = 1/ν [spec §7c]
    if (s.report.updated()) samples_ = s.lambda * samples_ + 1;
    return s.report;
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
  // s² = ν D_y/(n − ρ); NaN until n > ρ.
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
  double samples_ = 0;
  bool enabled_ = true;
};

using RecursiveLeastSquares = BasicRecursiveLeastSquares<Eigen::Dynamic>;

}  // namespace ident
