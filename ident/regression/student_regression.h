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
//   Cost per Update() (flops as counted in ident/regression/rls.h; m = ρ+1): the statistics steps of RLS without
//            β = 1/ν, except that the back substitution also forms r_i = 1/d_i and the running sums
//            Q_j = Σ_{i≥j} g_i² r_i (ξ_z = 1 − Q_1, ξ = 1 − Q_0; m divisions, 3m + 2 adds/multiplies) and
//            the plan of the update is taken from them (LdFactor::PlanUpdateFromSums: 11m + 1 instead of
//            12m + 2, m divisions instead of 2m + 1), and the update of L reuses the back substitution's
//            partial sums (LdFactor::CommitSolved: m(m−1) flops, not 2m(m−1)) — 2ρ² + 19ρ + 34 flops
//            (ρ = 4: 142), 2m divisions —
//            plus the weighting-cubic root, a ρ-independent cost (a bracketed iteration, usually one
//            Householder step; approx/weight_fast_path.h, inline); stabilised forgetting adds
//            ≈ (2/3)m³ + 4m² and a copy of L, d. No allocation after construction (also not at the
//            start-up restart).
//   Real-time loop features (as RLS, ident/regression/rls.h): set_enabled/enabled, Skip(), Reset() (noexcept,
//            allocation-free, back to a freshly built estimator's state), set_forgetting(λ) (refused
//            if inadmissible), CovarianceInto(P) (caller-owned ρ x ρ, ≈ (5/6)ρ³ flops).
//   Admissibility: every step needs ν(t) > ν_hard = max(ρ+δ−1, (k+3−δ)/k, ρ/(k+1)) [spec §5]. The
//            constructor checks this for every t ≥ 1 of the forgetting recursion and throws otherwise.
//
// Example:
//   ident::StudentRegressionOptions o;           // Cauchy (k = 1), δ = 1
//   o.prior = ident::RegressionPrior::Diagonal(/*rho=*/4, /*nu0=*/6, /*vy0=*/1, /*vz0=*/1e-3);
//   o.forgetting.factor = 0.99;
//   ident::BasicStudentRegression<4> est(/*num_parameters=*/4, o);   // fixed size; StudentRegression: dynamic
//   Eigen::Matrix4d P;
//   for (...) {
//     est.set_enabled(excitation_ok);
//     ident::StepReport r = sensor_ok ? est.Update(y, z) : est.Skip();   // r.weight = β(t)
//     est.CovarianceInto(P);
//   }
//   Eigen::Vector4d theta = est.parameters();
//
// References: M. Kárný, K. M. Hangos, Kybernetika 24(5), 1988; [spec] docs/explanation/cauchy-estimator-spec.md.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <string>

#include <fmt/core.h>
#include <Eigen/Core>

#include "approx/weight_fast_path.h"
#include "approx/weighting_polynomial.h"
#include "common/error.h"
#include "common/step_report.h"
#include "ident/regression/forgetting.h"
#include "ident/regression/internal/extended_information.h"
#include "ident/regression/internal/step_driver.h"
#include "ident/regression/regression_prior.h"

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
  // Leverage guard, for an outlying regressor: one the caller calls outlying (set_outlying_regressor;
  // by default every regressor), or one far out in the metric of the information matrix,
  // z'Ṽ_z⁻¹z = 1 − ξ_z > 25 + ρ (≈ ρ on average over the samples Ṽ_z summarises). For such a sample,
  // when H0 has two local maxima — "new information or outlier?" [spec §5] — take the outlier reading
  // (the smaller β); when it has one and the error is gross against the leverage (ê²/D_y above
  // 25·min(1, (25+ρ)/q), q = z'Ṽ_z⁻¹z: Schweppe's GM form, error times lever arm), take β0 = 1/(ν − (ν−1)ξ),
  // the smallest admissible weight, whose update β0·hh' adds the information of one ordinary sample
  // whatever the size of h. The maximin choice gives such a sample the weight of new information, an
  // influence that grows without bound with the size of the regressor (a gross output outlier entering
  // later ARX regressors); the guard bounds it, as GM-estimators bound leverage. A regressor that is new
  // and fitted by the model is learnt as usual; a new direction with a gross error is learnt one
  // ordinary sample's worth per sample. Switched per sample with set_leverage_guard.
  bool leverage_guard = false;
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

// "" if forgetting `f` keeps every ν(t), t ≥ 1, above ν_hard(ρ, k, δ) starting from ν(0) = nu0, else one
// line naming the inadmissible value [spec §5, §7b].
std::string ForgettingAdmissibility(int rho, double nu0, const ForgettingOptions& f, double dof, int delta);

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
  double elasticity = 0;  // ê·dβ/dê of the β taken, ξ_z fixed (PropagatedVariance)
};

// The scalar sandwich of M-estimation for the Student-t score (Huber 1981, §7.6). With u = ê²/D_y and the
// EM weight w = (k+1)/(k+u) [spec §7a]: ψ = w·ê, ψ' = (k+1)(k−u)/(k+u)². The one-sided recursion's V_z
// tends to E[w zz']/E[w] (the stationary point of V ← V + β(hh' − V) [spec §3]), so for noise independent
// of z the sandwich A⁻¹BA⁻¹ (A = Σψ'zz', B = Σψ²zz') is, with Huber's small-sample correction
// κ = 1 + (ρ/n)·var(ψ')/mean(ψ')² (Huber 1981, eq. 7.6.4; as MASS::rlm reports it),
//   Cov(Θ̂) ≈ c·V_z⁻¹/n,   c = κ²·n/(n−ρ)·mean(ψ²)/mean(ψ')².
// Under t_k noise of scale σ, c → σ²(k+3)/(k+1) (the inverse Fisher information; the posterior's
// D_y V_z⁻¹/(ν−δ−ρ) is smaller by that factor); under other noise c is what it is. The means run over the
// steps' own prediction errors ê (each against the estimate of its time), which also carries the extra
// variance of weighing every sample once, against that estimate. u = ξ_z − ξ of the step [spec §3].
// Sums are discounted by the step's λ. O(1) per update, no allocation.
struct SandwichFactor {
  double psi2 = 0, dpsi = 0, dpsi2 = 0, n = 0;

  void Add(double k, double u, double e, double lambda) noexcept {
    if (!(std::isfinite(u) && std::isfinite(e) && u >= 0)) return;
    const double r = 1 / (k + u), w = (k + 1) * r;  // one division: the step's own divisions queue for the divider
    psi2 = lambda * psi2 + w * w * e * e;
    const double d = w * (k - u) * r;
    dpsi = lambda * dpsi + d;
    dpsi2 = lambda * dpsi2 + d * d;
    n = lambda * n + 1;
  }
  // NaN until more than ρ+1 updates, or while mean(ψ') ≤ 0.
  double Factor(int rho) const noexcept {
    if (!(n > rho + 1 && dpsi > 0)) return std::numeric_limits<double>::quiet_NaN();
    const double mean = dpsi / n, kappa = 1 + rho / n * std::max(dpsi2 / n - mean * mean, 0.0) / (mean * mean);
    return kappa * kappa * n / (n - rho) * (psi2 / n) / (mean * mean);
  }
};

// The recursion's own sampling variance, propagated step by step: the delta method on the step
// Θ̂(t) = Θ̂(t−1) + g·Ṽ_z⁻¹z·ê, g = β/(1−βξ_z) [spec §3]. Its error δ(t) = Θ̂(t) − Θ is multiplied by
// I − γ·Ṽ_z⁻¹zz', γ = g + ê·dg/dê (the slope of the step's score g·ê, as ê = e − z'δ(t−1)), and gains
// g·e·Ṽ_z⁻¹z. With Cov(Θ̂) ≈ s·V_z⁻¹, each rank-one term Ṽ_z⁻¹zz'Ṽ_z⁻¹ is taken at its average over
// directions, (q/ρ)·V_z⁻¹, q = z'Ṽ_z⁻¹z = 1 − ξ_z; with c = γq/ρ:
//   s(t) = ((1 − c)² + (ρ−1)c²)·s(t−1) + (q/ρ)·g·ê·(g·ê + 2·A(t)·x),   A(t) = Π(1 − c) since the seed,
// where x is the sample's influence on the starting estimate when that estimate was fitted to samples
// the recursion then replays (zero otherwise): δ(0) = Σ x_i·Ṽ_z⁻¹z_i·(noise of sample i), so a replayed
// sample's two contributions add before they are squared. Unlike the M-estimation sandwich
// (SandwichFactor) this carries what weighing each sample once, against the estimate of its time,
// costs: a weight whose score slope γ·ν differs from 1 forgets the start slower or faster than 1/t,
// and the variance is then larger than the M-estimator's. O(1) per update.
struct PropagatedVariance {
  double s = 0, a = 1, x = 0;  // x: influence of the next sample on the seed (consumed by Add)
  void Seed(double s0) noexcept { s = s0, a = 1, x = 0; }
  void Add(double beta, double elasticity, double xi_z, double e, int rho) noexcept {
    const double r = 1 / (1 - beta * xi_z), q_rho = (1 - xi_z) / rho;  // two divisions (as SandwichFactor)
    const double g = beta * r, c = (g + elasticity * r * r) * q_rho, ge = g * e;
    const double influence = x;
    x = 0;
    if (!(std::isfinite(c) && std::isfinite(ge))) return;
    a *= 1 - c;
    // A(t) shrinks geometrically under forgetting. Below the normal range it would stay subnormal for good
    // (a·(1 − c) rounds back to a), and each operation on a subnormal takes the processor's slow path; its
    // term 2·a·x is then far below g·ê.
    if (!(std::abs(a) >= std::numeric_limits<double>::min())) a = 0;
    s = std::max(((1 - c) * (1 - c) + (rho - 1) * c * c) * s + q_rho * ge * (ge + 2 * a * influence), 0.0);
  }
};

template <int Rho = Eigen::Dynamic>
class BasicStudentRegression {
  static constexpr int kDim = Rho == Eigen::Dynamic ? Eigen::Dynamic : Rho + 1;

 public:
  using ParamVector = typename ExtendedInformation<kDim>::ParamVector;

  // Below this, d is taken to be winding up under forgetting (as in RLS; off with `exact`).
  static constexpr double kWindupFloor = 0x1p-900;

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
      provisional_prior_ = prior_;
      provisional_factor_ = prior_factor_;
      prior_diagonal_.resize(num_parameters + 1);
    }
  }

  // True while the data-driven start-up window is being collected.
  bool in_startup() const { return window_size_ > 0 && window_count_ < window_size_; }

  // One sample. A sample with a non-finite entry, a regressor of the wrong size or one that would
  // overflow is rejected (kRejectedInvalid, state unchanged); while disabled: kSkipped, state unchanged.
  // A step that would leave D not a positive normal number or L, Θ̂ not finite is undone
  // (kNumericalFailure, state unchanged), and — unless `exact` — a step under forgetting that would
  // push some d_i below kWindupFloor is retaken with λ = 1 (ident/regression/internal/step_driver.h). Never throws,
  // never allocates. During the start-up window (see StudentRegressionOptions::startup_window) the
  // reports come from the provisional prior.
  template <class Derived>
  StepReport Update(double y, const Eigen::MatrixBase<Derived>& z) noexcept {
    if (!enabled_) return {StepStatus::kSkipped};
    const StepReport report = Step(y, z);
    if (in_startup() && report.updated()) {
      window_(window_count_, 0) = y;
      window_.row(window_count_).tail(num_parameters()) = z.transpose();
      if (++window_count_ == window_size_) Restart();
    }
    return report;
  }

  // A missing sample: kSkipped, the state is untouched (the next Update() continues as if this
  // period had not happened).
  StepReport Skip() const noexcept { return {StepStatus::kSkipped}; }
  // Enable flag: while false, Update() skips every sample; read-outs keep working on the frozen state.
  void set_enabled(bool enabled) noexcept { enabled_ = enabled; }
  bool enabled() const noexcept { return enabled_; }

  // Back to the state of a freshly built estimator with the same options (keeping the enable flag and
  // the current forgetting factor): the prior (ν0, V0) — with the data-driven start-up, the provisional
  // prior and an empty window, collected again. noexcept, allocation-free.
  void Reset() noexcept {
    if (window_size_ > 0) {
      prior_.nu0 = provisional_prior_.nu0;
      prior_.V0 = provisional_prior_.V0;  // same size: no allocation
      prior_factor_ = provisional_factor_;
      window_count_ = 0;
    }
    stats_.Reset(prior_.nu0, prior_factor_);
    sandwich_ = {};
    propagated_.Seed(PriorVarianceFactor());
    last_beta_ = std::numeric_limits<double>::quiet_NaN();
    details_ = {};
  }

  // Switches the leverage guard (StudentRegressionOptions::leverage_guard) for the next updates. noexcept.
  void set_leverage_guard(bool on) noexcept { options_.leverage_guard = on; }
  // Whether the guard treats the next regressors as outlying whatever their metric distance (default
  // true: every regressor, the guard's behaviour when the caller gives no verdict). noexcept.
  void set_outlying_regressor(bool outlying) noexcept { outlying_regressor_ = outlying; }
  // Robust scales (in the metric z'Ṽ_z⁻¹z: its square, plus ρ) beyond which a regressor is outlying, and
  // prediction errors (ê²/D_y beyond its square, scaled down by the leverage) that are gross, for the
  // leverage guard.
  static constexpr double kLeverage = 5;

  // Changes λ on the fly (the next update uses it). Throws InvalidArgument if λ ∉ (0, 1] or if λ is
  // inadmissible — ν(t) would reach ν_hard from the current ν or from ν(0) after a Reset() [spec §5, §7b].
  // No allocation otherwise.
  void set_forgetting(double lambda) {
    ForgettingOptions f = options_.forgetting;
    f.factor = lambda;
    std::string error = f.Validate();
    if (error.empty()) error = ForgettingAdmissibility(num_parameters(), prior_.nu0, f, options_.dof, options_.delta);
    if (error.empty()) {
      const double nu_next =
          f.stabilised ? lambda * stats_.nu() + (1 - lambda) * prior_.nu0 + 1 : lambda * stats_.nu() + 1;
      if (!(nu_next > nu_hard_))
        error = fmt::format("forgetting = {} is inadmissible now: the next step has nu = {} <= nu_hard = {}", lambda,
                            nu_next, nu_hard_);
    }
    IDENT_REQUIRE(error.empty(), "{}", error);
    options_.forgetting = f;
  }

 private:
  template <class Derived>
  StepReport Step(double y, const Eigen::MatrixBase<Derived>& z) noexcept {
    const StepSettings settings{options_.forgetting.factor, options_.forgetting.stabilised,
                                options_.exact ? 0.0 : kWindupFloor};
    const DrivenStep s = driver_.Run(stats_, settings, prior_.nu0, prior_factor_, y, z,  // [spec §7b, §6]
                                     [this](double nu, const Innovation& in) { return Weight(nu, in); });
    if (s.report.updated()) {
      last_beta_ = s.report.weight;
      sandwich_.Add(options_.dof, details_.xi_z - details_.xi, s.report.prediction_error, s.lambda);
      propagated_.Add(s.report.weight, details_.elasticity, details_.xi_z, s.report.prediction_error, num_parameters());
    }
    return s.report;
  }

  // β(t): the maximin root of the weighting cubic [spec §4, §5]; NaN (step refused) if it fails —
  // not observed for ν > ν_hard, which the constructor and set_forgetting guarantee.
  double Weight(double nu, const Innovation& in) noexcept {
    if (!(nu > nu_hard_)) return std::numeric_limits<double>::quiet_NaN();
    const approx::WeightingProblem problem{nu, in.xi, in.xi_z, num_parameters(), options_.dof, options_.delta};
    if (!(nu == weight_constants_.nu)) weight_constants_.Set(problem);  // ν(t) settles under forgetting
    const approx::WeightSolution w = approx::SolveWeightInline(problem, weight_constants_);  // = SolveWeight
    details_ = {in.xi, in.xi_z, w.beta0, w.beta_hi, w.num_maxima};
    if (!w.ok) return std::numeric_limits<double>::quiet_NaN();
    // The guard acts on a regressor the caller calls outlying, or one far out in the metric of the
    // information matrix: z'Ṽ_z⁻¹z = 1 − ξ_z, ≈ ρ on average over the samples Ṽ_z summarises.
    if (!options_.leverage_guard || !(outlying_regressor_ || 1 - in.xi_z > kLeverage * kLeverage + num_parameters()))
      return RootElasticity(problem, w.beta);
    if (w.num_maxima > 1) return RootElasticity(problem, w.smallest_maximum);  // the outlier reading [spec §5]
    // One maximum, a gross error: the smallest admissible weight β0 = 1/(ν − (ν−1)ξ), ξ = 1 − h'Ṽ⁻¹h,
    // whose update β0·hh' has β0·h'Ṽ⁻¹h = (1−ξ)/(1 + (ν−1)(1−ξ)) < 1/(ν−1) in the metric of Ṽ: the
    // information of one ordinary sample, whatever the size of h.
    // "Gross" is judged against the leverage (Schweppe's GM form): ê²/D_y beyond 25·min(1, (25+ρ)/q), so
    // beyond the leverage limit the product of error and lever arm, not the error alone, decides.
    const double q = 1 - in.xi_z, limit = kLeverage * kLeverage + num_parameters();
    if (!(in.xi_z - in.xi > kLeverage * kLeverage * std::min(1.0, limit / q))) return RootElasticity(problem, w.beta);
    // β0 = 1/(ν − (ν−1)ξ) for ξ < 0: dβ0/dξ = (ν−1)β0², dξ/dê = −2ê/D_y.
    details_.elasticity = in.xi < 0 ? -2 * (in.xi_z - in.xi) * (nu - 1) * w.beta0 * w.beta0 : 0;
    return w.beta0;
  }

  // β, recording ê·dβ/dê (approx::WeightElasticity) for a root β of the weighting cubic.
  double RootElasticity(const approx::WeightingProblem& problem, double beta) noexcept {
    const double e = approx::WeightElasticityInline(problem, weight_constants_, beta);  // of problem.nu (Weight())
    details_.elasticity = std::isfinite(e) ? e : 0;
    return beta;
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

  // The data-driven prior from the window, then replay of the window (see the options). The prior is
  // diagonal, so its factor is L = I, d = diag V(0) (no factorisation, no allocation). If some diagonal
  // entry is not within [kWindupFloor, 1/kWindupFloor] (robust scales of samples ~1e-150 square to
  // subnormals, of ~1e154 to infinity), the restart is skipped: the estimator continues from the
  // provisional prior it has run the window on (fuzz finding, fuzz/corpus/student_fuzzer).
  void Restart() noexcept {
    const int rho = num_parameters();
    const double nu0 = rho + options_.dof + options_.delta;
    auto& v0 = prior_diagonal_;  // sized at construction
    const double sy = RobustScale(0);
    v0(0) = sy * sy;
    for (int i = 1; i <= rho; ++i) {
      const double sz = RobustScale(i);
      v0(i) = sz * sz / (100 * (nu0 - options_.delta - rho));
    }
    if (!((v0.array() >= kWindupFloor).all() && (v0.array() <= 1 / kWindupFloor).all())) return;
    prior_.nu0 = nu0;
    prior_.V0.setZero();
    prior_.V0.diagonal() = v0;
    prior_factor_.SetDiagonal(v0);
    stats_.Reset(nu0, prior_factor_);
    sandwich_ = {};
    propagated_.Seed(PriorVarianceFactor());
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
  // The sampling covariance of Θ̂, whatever the noise law: the larger of the recursion's propagated
  // variance (PropagatedVariance) and the sandwich c·V_z⁻¹/n of M-estimation (SandwichFactor), the
  // M-estimator's own, which no single pass with the same score beats (its excess over the sandwich is
  // γ̄²/(2γ̄−1) ≥ 1 asymptotically, γ̄ = E[γ]·ν); the sandwich alone once use_sandwich_covariance() is
  // set. +inf entries until more than ρ+1 updates. posterior_covariance() is the one-sided posterior's
  // own D_y V_z⁻¹/(ν−δ−ρ), too small by (k+3)/(k+1) even under the model.
  Eigen::MatrixXd covariance() const {
    Eigen::MatrixXd out(num_parameters(), num_parameters());
    CovarianceInto(out);
    return out;
  }
  // The same covariance into a caller-owned ρ x ρ matrix, without allocating, at any time. ~(5/6)ρ³
  // flops. Throws InvalidArgument only if `out` has the wrong size.
  void CovarianceInto(Eigen::Ref<Eigen::MatrixXd> out) const {
    const double sandwich = sandwich_.Factor(num_parameters()) / sandwich_.n;  // NaN until ρ+1 updates
    ScaledVzInverseOrInfinity(sandwich_covariance_ || !(propagated_.s > sandwich) ? sandwich : propagated_.s, out);
  }
  // covariance() from the M-estimation sandwich alone: for an estimate that has settled at the
  // M-estimator's fixed point, after further passes over the same samples, which the propagation would
  // count twice.
  void use_sandwich_covariance(bool on) noexcept { sandwich_covariance_ = on; }
  // Seeds the propagated variance (PropagatedVariance) with the variance factor s0 of the starting
  // estimate, and gives the influence x of the next sample on it (for a start fitted to samples that are
  // then replayed). Without a seed, s0 is the prior's own D_y(0)/(ν0−δ−ρ).
  void SeedPropagatedVariance(double s0) noexcept { propagated_.Seed(s0); }
  void set_start_influence(double x) noexcept { propagated_.x = x; }
  // Cov(Θ) of the one-sided posterior: D_y V_z⁻¹/(ν−δ−ρ) (multivariate t, ν−δ−ρ+2 d.o.f.) [spec §2];
  // +inf entries while ν ≤ δ+ρ.
  Eigen::MatrixXd posterior_covariance() const {
    Eigen::MatrixXd out(num_parameters(), num_parameters());
    PosteriorCovarianceInto(out);
    return out;
  }
  void PosteriorCovarianceInto(Eigen::Ref<Eigen::MatrixXd> out) const {
    ScaledVzInverseOrInfinity(stats_.Dy() / (stats_.nu() - options_.delta - num_parameters()), out);
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

 private:
  // D_y/(ν−δ−ρ), the one-sided posterior's covariance factor; +inf while ν ≤ δ+ρ.
  double PriorVarianceFactor() const noexcept {
    const double dof = stats_.nu() - options_.delta - num_parameters();
    return dof > 0 ? stats_.Dy() / dof : std::numeric_limits<double>::infinity();
  }
  // out = s·V_z⁻¹, or +inf entries unless s is positive and finite. Throws only for a wrong size.
  void ScaledVzInverseOrInfinity(double s, Eigen::Ref<Eigen::MatrixXd> out) const {
    IDENT_REQUIRE(out.rows() == num_parameters() && out.cols() == num_parameters(),
                  "covariance output is {}x{}; need {}x{}", out.rows(), out.cols(), num_parameters(), num_parameters());
    if (!(s > 0 && std::isfinite(s)))
      out.setConstant(std::numeric_limits<double>::infinity());
    else
      stats_.ScaledVzInverse(s, out);
  }
  static const StudentRegressionOptions& Checked(int num_parameters, const StudentRegressionOptions& options) {
    const std::string error = options.Validate(num_parameters);
    IDENT_REQUIRE(error.empty(), "{}", error);
    return options;
  }

  StudentRegressionOptions options_;
  RegressionPrior prior_;
  ExtendedInformation<kDim> stats_;
  StepDriver<kDim> driver_{stats_};
  LdFactor<kDim> prior_factor_;
  double nu_hard_ = approx::NuHard(stats_.num_parameters(), options_.dof, options_.delta);
  double last_beta_ = std::numeric_limits<double>::quiet_NaN();
  bool outlying_regressor_ = true;
  StudentStepDetails details_;
  approx::WeightConstants weight_constants_;  // of the last ν(t) (Weight())
  SandwichFactor sandwich_;
  PropagatedVariance propagated_{PriorVarianceFactor()};
  bool sandwich_covariance_ = false;
  bool enabled_ = true;
  int window_size_ = 0, window_count_ = 0;  // data-driven start-up (0 = off)
  Eigen::MatrixXd window_;                  // W x (ρ+1): y, z of the first W samples
  Eigen::VectorXd scratch_;
  RegressionPrior provisional_prior_;  // the prior before the start-up window (for Reset)
  LdFactor<kDim> provisional_factor_;
  Eigen::Matrix<double, kDim, 1> prior_diagonal_;  // Restart() workspace
};

using StudentRegression = BasicStudentRegression<Eigen::Dynamic>;

}  // namespace ident
