// Recursive regression with Student-t (k d.o.f.) or Cauchy (k = 1) noise: the Kárný–Hangos
// one-sided maximin approximation of Bayes' rule, on the LD-factorised extended information matrix.
//
//   Model:   y(t) = Θ'z(t) + e(t),  m(t|w) ∝ ω^{1/2}(1 + ω(θ̃'h)²)^{−κ},  κ = (k+1)/2,
//            θ̃ = [−1; Θ], h = [y; z]                                                       [spec §1]
//   Class:   l(w|t) ∝ ω^{ν/2}(1 + ω θ̃'V(t)θ̃)^{−κν} w.r.t. ω^{−δ/2}dΘdω                       [spec §2]
//   Step:    forgetting (ν̃, Ṽ) [spec §7b]; ν(t) = ν̃ + 1; ξ, ξ_z, ê by one back substitution [spec §6];
//            β = maximin root of the weighting cubic in [β0, β_hi] [spec §4, §5];
//            V(t) = (1−β)Ṽ + βhh' (d ← (1−β)d, then the rank-one update)                   [spec §3, §6]
//   Read-outs: Θ̂ = V_z⁻¹V_zy; D_y = |V|/|V_z| (→ σ², the squared t-scale); Cov(Θ) = D_y V_z⁻¹/(ν−δ−ρ)
//            (multivariate t with ν−δ−ρ+2 d.o.f.) [spec §2]; β(t), ν(t) of the last step; a predictive
//            t distribution of the next y (see Predictive()).
//   Cost:    O(ρ²) per update (~3(ρ+1)² flops plus a fixed-cost cubic root), no allocation.
//   Admissibility: every step needs ν(t) > ν_hard = max(ρ+δ−1, (k+3−δ)/k, ρ/(k+1)) [spec §5]. The
//            constructor checks this for every t ≥ 1 of the forgetting recursion and throws otherwise.
//
// Example:
//   ident::StudentRegressionOptions o;           // Cauchy (k = 1), δ = 1
//   o.prior = ident::RegressionPrior::Diagonal(/*rho=*/4, /*nu0=*/6, /*vy0=*/1, /*vz0=*/1e-3);
//   ident::StudentRegression est(/*num_parameters=*/4, o);
//   for (...) ident::StepReport r = est.Update(y, z);    // r.weight = β(t)
//   Eigen::VectorXd theta = est.parameters();
//
// References: M. Kárný, K. M. Hangos, Kybernetika 24(5), 1988; [spec] shared/spec/cauchy-estimator.md.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <string>

#include <Eigen/Core>

#include "approx/weighting_polynomial.h"
#include "ident/common/error.h"
#include "ident/common/step_report.h"
#include "ident/extended_information.h"
#include "ident/forgetting.h"
#include "ident/regression_prior.h"

namespace ident {

struct StudentRegressionOptions {
  double dof = 1.0;  // k > 0; 1 = Cauchy (the paper), large = Gaussian
  int delta = 1;     // ω-exponent convention δ ∈ {0, 1}; 1 = the paper's algorithm [spec §2.1]
  ForgettingOptions forgetting;
  // (ν(0), V(0)). Default (unless `exact`): the data-driven start-up prior below; with `exact`:
  // ν(0) = ρ+k+δ (spec §8) and V(0) = diag(1, 1e-3·I).
  std::optional<RegressionPrior> prior;
  // Only the spec's recursion: no data-driven start-up (the command line's --exact).
  bool exact = false;
  // Data-driven start-up (used when `prior` is unset and not `exact`): the first W samples are run
  // with DefaultPrior() and kept; after sample W the estimator restarts from the prior
  //   ν(0) = ρ+k+δ,  Θ0 = 0,  σ0 = s_y,  V_y(0) = s_y²,  V_z(0) = diag(s_{z_i}²)/(100·(ν0−δ−ρ)),
  // i.e. the spec §8 recipe with P0 = diag((10·s_y/s_{z_i})²), where s = 1.4826·MAD (median absolute
  // deviation from the median) over the window (RMS if the MAD is 0, 1 if that is 0 too), and replays
  // the W samples. s_y over-estimates the noise scale (it includes the signal), the safe side of spec §8's
  // hazard, and ignores up to half the window being outliers. 0 = W = max(20, 4ρ).
  int startup_window = 0;

  // The default prior of spec §8 for ρ parameters: ν(0) = ρ+k+δ, V(0) = diag(1, 1e-3·I).
  RegressionPrior DefaultPrior(int num_parameters) const;
  // "" if valid for ρ parameters, else one line naming the option (including the admissibility
  // ν(t) > ν_hard for every t ≥ 1 under the chosen forgetting).
  std::string Validate(int num_parameters) const;
};

// The predictive distribution of the next y given z: Student-t with `dof` degrees of freedom,
// location Θ̂'z and squared scale D_y·(1 + z'V_z⁻¹z/(ν−δ−ρ)) — the noise scale widened by the
// parameter uncertainty Cov(Θ) of spec §2 (a moment-style approximation, exact in the Gaussian limit).
struct Predictive {
  double location = 0;
  double scale = 0;
  double dof = 0;
};

// The step quantities of the last update (for traces and tests), all computed against Ṽ [spec §11].
struct StudentStepDetails {
  double xi = std::numeric_limits<double>::quiet_NaN();
  double xi_z = std::numeric_limits<double>::quiet_NaN();
  double beta0 = std::numeric_limits<double>::quiet_NaN();
  double beta_hi = std::numeric_limits<double>::quiet_NaN();
  int num_maxima = 0;
};

template <int Rho = Eigen::Dynamic>
class BasicStudentRegression {
  static constexpr int kDim = Rho == Eigen::Dynamic ? Eigen::Dynamic : Rho + 1;

 public:
  using ParamVector = typename ExtendedInformation<kDim>::ParamVector;

  // Throws InvalidArgument naming the option if `options` is invalid or inadmissible.
  explicit BasicStudentRegression(int num_parameters, const StudentRegressionOptions& options = {})
      : options_(Checked(num_parameters, options)),
        prior_(options_.prior ? *options_.prior : options_.DefaultPrior(num_parameters)),
        stats_(prior_),
        prior_factor_(prior_.V0) {
    if (!options_.prior && !options_.exact) {
      window_size_ = options_.startup_window > 0 ? options_.startup_window : std::max(20, 4 * num_parameters);
      window_.resize(window_size_, num_parameters + 1);
      scratch_.resize(window_size_);
    }
  }

  // True while the data-driven start-up window is being collected.
  bool in_startup() const { return window_size_ > 0 && window_count_ < window_size_; }

  // One sample. A sample with a non-finite entry, a regressor of the wrong size or one that would
  // overflow is rejected (state unchanged). Never throws, never allocates.
  // During the start-up window (see StudentRegressionOptions::startup_window) the reports come from the
  // provisional prior; the restart after sample W allocates once (prior validation).
  template <class Derived>
  StepReport Update(double y, const Eigen::MatrixBase<Derived>& z) noexcept {
    if (z.size() != num_parameters() || !std::isfinite(y) || !z.allFinite() ||
        !std::isfinite(y * y + z.squaredNorm()))
      return {StepStatus::kRejectedInvalid};
    const StepReport report = Step(y, z);
    if (in_startup() && report.updated()) {
      window_(window_count_, 0) = y;
      window_.row(window_count_).tail(num_parameters()) = z.transpose();
      if (++window_count_ == window_size_) Restart();
    }
    return report;
  }

 private:
  template <class Derived>
  StepReport Step(double y, const Eigen::MatrixBase<Derived>& z) noexcept {
    const double lambda = options_.forgetting.factor;
    const double nu_tilde =
        options_.forgetting.stabilised ? lambda * stats_.nu() + (1 - lambda) * prior_.nu0 : lambda * stats_.nu();
    if (!(nu_tilde + 1 > nu_hard_))  // cannot happen: admissibility is checked at construction [spec §5]
      return {StepStatus::kNumericalFailure, std::numeric_limits<double>::quiet_NaN(), nu_tilde + 1};
    if (options_.forgetting.stabilised)
      stats_.ForgetStabilised(lambda, prior_.nu0, prior_factor_);  // [spec §7b]
    else
      stats_.ForgetExponential(lambda);  // [spec §7b]
    const double nu = stats_.nu() + 1;
    const Innovation in = stats_.Prepare(y, z);  // ξ, ξ_z, ê [spec §6]
    const approx::WeightingProblem problem{nu, in.xi, in.xi_z, num_parameters(), options_.dof, options_.delta};
    const approx::WeightSolution w = approx::SolveWeight(problem);  // [spec §4, §5]
    details_ = {in.xi, in.xi_z, w.beta0, w.beta_hi, w.num_maxima};
    if (!w.ok || !(w.beta > 0 && w.beta < 1))  // not observed for ν > ν_hard; state is forgotten only
      return {StepStatus::kNumericalFailure, w.beta, nu, in.prediction_error};
    stats_.Apply(w.beta, nu);  // V(t) = (1−β)Ṽ + βhh' [spec §3 step 5]
    last_beta_ = w.beta;
    return {StepStatus::kUpdated, w.beta, nu, in.prediction_error};
  }

  // s = 1.4826·MAD of column c of the window (RMS if 0, else 1).
  double RobustScale(int c) {
    const int n = window_size_;
    scratch_ = window_.col(c);
    std::nth_element(scratch_.data(), scratch_.data() + n / 2, scratch_.data() + n);
    const double med = scratch_(n / 2);
    scratch_ = (window_.col(c).array() - med).abs();
    std::nth_element(scratch_.data(), scratch_.data() + n / 2, scratch_.data() + n);
    double s = 1.4826 * scratch_(n / 2);
    if (!(s > 0)) s = std::sqrt(window_.col(c).squaredNorm() / n);
    return s > 0 ? s : 1.0;
  }

  // The data-driven prior from the window, then replay of the window (see the options).
  void Restart() noexcept {
    const int rho = num_parameters();
    const double sy = RobustScale(0);
    const double nu0 = rho + options_.dof + options_.delta;
    prior_.nu0 = nu0;
    prior_.V0.setZero();
    prior_.V0(0, 0) = sy * sy;
    for (int i = 1; i <= rho; ++i) {
      const double sz = RobustScale(i);
      prior_.V0(i, i) = sz * sz / (100 * (nu0 - options_.delta - rho));
    }
    try {
      stats_.Reset(prior_);
      prior_factor_.Factorize(prior_.V0);
    } catch (...) {  // cannot happen: V0 is diagonal with positive entries
      return;
    }
    for (int t = 0; t < window_size_; ++t) Step(window_(t, 0), window_.row(t).tail(rho).transpose());
  }

 public:
  int num_parameters() const { return stats_.num_parameters(); }
  const ParamVector& parameters() const { return stats_.parameters(); }
  template <class Derived>
  double Predict(const Eigen::MatrixBase<Derived>& z) const {
    return stats_.Predict(z);
  }
  double nu() const { return stats_.nu(); }
  double Dy() const { return stats_.Dy(); }
  // β(t) of the last update (NaN before the first).
  double beta() const { return last_beta_; }
  const StudentStepDetails& last_step() const { return details_; }
  // The noise scale σ (D_y → σ² for large ν [spec §2]).
  double noise_std() const { return std::sqrt(stats_.Dy()); }
  // Cov(Θ) = D_y V_z⁻¹/(ν−δ−ρ) (multivariate t, ν−δ−ρ+2 d.o.f.); +inf entries while ν ≤ δ+ρ.
  Eigen::MatrixXd covariance() const {
    const double dof = stats_.nu() - options_.delta - num_parameters();
    if (!(dof > 0))
      return Eigen::MatrixXd::Constant(num_parameters(), num_parameters(), std::numeric_limits<double>::infinity());
    return stats_.Dy() / dof * stats_.VzInverse();
  }
  // Degrees of freedom of the multivariate-t marginal of Θ: ν−δ−ρ+2 [spec §2].
  double parameter_dof() const { return stats_.nu() - options_.delta - num_parameters() + 2; }
  template <class Derived>
  Predictive PredictDistribution(const Eigen::MatrixBase<Derived>& z) const {
    const Eigen::VectorXd zz = z;
    const double dof = stats_.nu() - options_.delta - num_parameters();
    const double zeta = zz.dot(stats_.VzInverse() * zz);
    const double widen = dof > 0 ? 1 + zeta / dof : std::numeric_limits<double>::infinity();
    return {stats_.Predict(zz), std::sqrt(stats_.Dy() * widen), options_.dof};
  }
  double nu_hard() const { return nu_hard_; }
  const ExtendedInformation<kDim>& statistics() const { return stats_; }
  const StudentRegressionOptions& options() const { return options_; }
  const RegressionPrior& prior() const { return prior_; }

  // Back to the prior (the data-driven one, if the start-up window was completed).
  void Reset() {
    stats_.Reset(prior_);
    last_beta_ = std::numeric_limits<double>::quiet_NaN();
    details_ = {};
  }

 private:
  static const StudentRegressionOptions& Checked(int num_parameters, const StudentRegressionOptions& options) {
    const std::string error = options.Validate(num_parameters);
    IDENT_REQUIRE(error.empty(), "{}", error);
    return options;
  }

  StudentRegressionOptions options_;
  RegressionPrior prior_;
  ExtendedInformation<kDim> stats_;
  LdFactor<kDim> prior_factor_;
  double nu_hard_ = approx::NuHard(stats_.num_parameters(), options_.dof, options_.delta);
  double last_beta_ = std::numeric_limits<double>::quiet_NaN();
  StudentStepDetails details_;
  int window_size_ = 0, window_count_ = 0;  // data-driven start-up (0 = off)
  Eigen::MatrixXd window_;                  // W x (ρ+1): y, z of the first W samples
  Eigen::VectorXd scratch_;
};

using StudentRegression = BasicStudentRegression<Eigen::Dynamic>;

}  // namespace ident
