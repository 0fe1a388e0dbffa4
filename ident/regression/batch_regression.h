// Batch robust regression references: Huber M-estimation as MASS::rlm computes it, and the Cauchy
// maximum-likelihood fit of (Θ, γ) jointly from many starts; the gold standard beside the recursive
// estimators on outlier data.
//
//   Model:   y_i = Θ'z_i + e_i, i = 1..n, with ρ regressors (an intercept is a constant-1 column of Z);
//            r_i = y_i − Θ'z_i.
//   Huber:   minimise Σ ρ_k(r_i/s), ρ_k(u) = u²/2 (|u| ≤ k), k|u| − k²/2 (else), k = 1.345, by IRLS from
//            the least-squares fit, as MASS::rlm's default: every iteration s = median|r|/0.6745 of the
//            current residuals, weights w_i = min(1, k s/|r_i|), weighted least squares for Θ; stop when
//            ‖r_new − r_old‖/min(‖r_old‖, √n·s) ≤ tolerance (rlm's irls.delta divides by ‖r_old‖ alone, and
//            stops at 1e-4 or after 20 steps; a gross error then dominates ‖r_old‖ and stops the iteration
//            far from the fixed point; here 1e-12 by default). Cov(Θ̂) = κ² s² [Σψ(u_i)²/(n−ρ)] / [Σψ'(u_i)/n]² (Z'Z)⁻¹,
//            u_i = r_i/s, κ = 1 + ρ var(ψ')/(n mean(ψ')²) with var's n−1 denominator (summary.rlm).
//   Cauchy:  minimise the negative log-likelihood NLL(Θ, γ) = Σ log(γ² + r_i²) − n log γ + n log π. It is
//            multimodal: starts are random elemental subsets (ρ rows solved exactly), LTS fits
//            (concentration steps on the h = ⌊(n+ρ+1)/2⌋ smallest squared residuals from random
//            elemental subsets) and least squares; from each, EM for the t distribution with k = 1
//            (w_i = 2/(1 + r_i²/γ²), weighted least squares for Θ, γ² = Σ w_i r_i²/n) for a few steps;
//            the best distinct ones continue with Newton on (Θ, log γ) (analytic gradient and Hessian,
//            backtracking, an EM step where the Hessian is not positive definite) until the scaled
//            gradient ‖(γ ∂/∂Θ̃, ∂/∂log γ)‖ is below gradient_tolerance; the lowest NLL wins.
//            Cov(Θ̂) = A⁻¹BA⁻¹, A = Σ ψ'(r_i) z_i z_i', B = Σ ψ(r_i)² z_i z_i', ψ(r) = 2r/(γ² + r²) (the
//            sandwich), or the Θ block of the inverse observed information in (Θ, log γ) if A is not
//            positive definite.
//   Numerics: both work in the orthonormal coordinates of a thin QR factorisation Z = QR (β = RΘ), so
//            that regressors of mixed scale or nearly collinear with the intercept (a calendar year)
//            cost no accuracy; Θ̃ above is β. Random subsets come from std::mt19937_64 with a fixed seed
//            and a rejection-sampled index (no std distribution), so they are the same on every platform.
//   Cost:    Huber O(nρ²) per iteration. Cauchy O(nρ²) per EM or Newton step, about
//            (starts × screening_iterations + polished × iterations) steps; the time of a fit
//            is in bench/batch_regression_benchmark.cc.
//
// BatchRegressionEstimator wraps either behind the RegressionEstimator concept
// (ident/regression/regression_estimator.h): Update() stores the sample, the read-outs solve the whole batch lazily
// (cached until the next sample).
//
// Example:
//   Eigen::MatrixXd Z(n, 2);   // [1, x_i]
//   Eigen::VectorXd y(n);
//   ident::BatchRegressionResult h = ident::HuberRegression(Z, y);         // = MASS::rlm(y ~ x)
//   ident::BatchRegressionResult c = ident::CauchyMlRegression(Z, y);      // global Cauchy ML
//   double gamma = c.scale;
//   Eigen::VectorXd se = c.covariance.diagonal().cwiseSqrt();
//
//   ident::BatchRegressionOptions options;
//   options.method = ident::BatchMethod::kCauchyMl;
//   ident::BatchRegressionEstimator est(/*num_parameters=*/2, options);
//   for (...) est.Update(y_t, z_t);
//   Eigen::VectorXd theta = est.parameters();   // solves all samples so far
//
// References: P. J. Huber, Robust Statistics, Wiley 1981; W. N. Venables, B. D. Ripley, Modern Applied
// Statistics with S, 4th ed., Springer 2002 (MASS::rlm, summary.rlm); P. J. Rousseeuw, A. M. Leroy, Robust
// Regression and Outlier Detection, Wiley 1987 (elemental subsets, LTS); C. Liu, D. B. Rubin, Statistica
// Sinica 5, 1995 (EM for the t distribution).
#pragma once

#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "common/error.h"
#include "common/step_report.h"

namespace ident {

struct BatchRegressionResult {
  Eigen::VectorXd theta;       // Θ̂ (ρ)
  double scale = 0;            // Huber: the MAD scale s of the last iteration; Cauchy: γ
  Eigen::MatrixXd covariance;  // Cov(Θ̂), ρ x ρ (see the header comment)
  double objective = 0;        // Huber: Σ ρ_k(r_i/s); Cauchy: the NLL with n log π
  int iterations = 0;          // Huber: IRLS steps; Cauchy: EM + Newton steps of the winning start
  int starts = 0;              // starts tried (Huber: 1, the least-squares fit)
  bool converged = false;      // the stopping rule was met within max_iterations
  double gradient_norm = 0;    // Cauchy: the scaled gradient at Θ̂ (see the header comment); Huber: 0
};

struct HuberOptions {
  double k = 1.345;  // ψ's corner, in units of s
  double tolerance = 1e-12;  // on ‖r_new − r_old‖/min(‖r_old‖, √n·s); MASS::rlm: 1e-4 on ‖r_new − r_old‖/‖r_old‖
  int max_iterations = 1000;  // MASS::rlm: 20

  // "" if valid, else one line naming the option.
  std::string Validate() const;
};

struct CauchyMlOptions {
  static constexpr int kAuto = -1;
  int elemental_starts = kAuto;   // random elemental subsets; kAuto = max(50, 20ρ)
  int lts_starts = 5;             // LTS fits from random elemental subsets
  bool ls_start = true;           // the least-squares fit as a start
  int screening_iterations = 10;  // EM steps from every start before the best are chosen
  int polished = 5;               // best distinct screened starts taken on to convergence
  double gradient_tolerance = 1e-10;
  int max_iterations = 500;  // EM + Newton steps of one polished start
  std::uint64_t seed = 0x5eed'1de7'0bad'cafeULL;

  // "" if valid, else one line naming the option.
  std::string Validate() const;
};

// Both throw InvalidArgument naming the problem unless Z is n x ρ and y has n entries, all finite, n > ρ ≥ 1
// and Z has full column rank (and the options are valid). If y = ZΘ exactly, CauchyMlRegression returns that
// Θ with scale 0, a zero covariance, objective −inf and converged = false (the likelihood is unbounded).
BatchRegressionResult HuberRegression(const Eigen::Ref<const Eigen::MatrixXd>& Z,
                                      const Eigen::Ref<const Eigen::VectorXd>& y, const HuberOptions& options = {});
BatchRegressionResult CauchyMlRegression(const Eigen::Ref<const Eigen::MatrixXd>& Z,
                                         const Eigen::Ref<const Eigen::VectorXd>& y,
                                         const CauchyMlOptions& options = {});

// The Cauchy NLL Σ log(γ² + r_i²) − n log γ + n log π at (Θ, γ).
double CauchyNegativeLogLikelihood(const Eigen::Ref<const Eigen::MatrixXd>& Z,
                                   const Eigen::Ref<const Eigen::VectorXd>& y,
                                   const Eigen::Ref<const Eigen::VectorXd>& theta, double gamma);

enum class BatchMethod { kHuber, kCauchyMl };

struct BatchRegressionOptions {
  BatchMethod method = BatchMethod::kHuber;
  HuberOptions huber;
  CauchyMlOptions cauchy;
};

// The batch estimators behind the RegressionEstimator concept. Update() appends the sample (O(ρ), amortised;
// the store grows); parameters(), covariance(), Dy(), noise_std() and Predict() solve all stored samples on
// first use after new samples arrived and cache the result. Until ρ+1 samples with full-rank regressors are
// stored: Θ̂ = 0, covariance +inf, Dy and noise_std NaN.
class BatchRegressionEstimator {
 public:
  // Throws InvalidArgument for num_parameters < 1 or invalid options.
  explicit BatchRegressionEstimator(int num_parameters, const BatchRegressionOptions& options = {});

  // Stores (y, z): kUpdated with weight 1/n, nu = n and prediction_error = y − Θ̂'z from the last solved Θ̂
  // (0 if none; no solve here). A non-finite entry or a regressor of the wrong size: kRejectedInvalid,
  // nothing stored.
  template <class Derived>
  StepReport Update(double y, const Eigen::MatrixBase<Derived>& z) {
    if (z.size() != num_parameters_ || !std::isfinite(y) || !z.allFinite()) return {StepStatus::kRejectedInvalid};
    const double error = y - cache_.theta.dot(z.derived().template cast<double>());
    y_.push_back(y);
    for (Eigen::Index i = 0; i < z.size(); ++i) z_.push_back(static_cast<double>(z.derived()(i)));
    solved_ = false;
    const double n = static_cast<double>(y_.size());
    return {StepStatus::kUpdated, 1 / n, n, error};
  }

  int num_parameters() const { return num_parameters_; }
  const Eigen::VectorXd& parameters() const { return Solved().theta; }
  Eigen::MatrixXd covariance() const { return Solved().covariance; }
  // θ̂'z; throws InvalidArgument if z does not have one entry per parameter.
  template <class Derived>
  double Predict(const Eigen::MatrixBase<Derived>& z) const {
    IDENT_REQUIRE(z.size() == num_parameters_, "Predict: z has {} entries; the model has {} parameters", z.size(),
                  num_parameters_);
    return parameters().dot(z.derived().template cast<double>());
  }
  double nu() const { return static_cast<double>(y_.size()); }
  double Dy() const { return noise_std() * noise_std(); }
  double noise_std() const { return Solved().scale; }
  // The whole result of the last solve (solving first if needed).
  const BatchRegressionResult& result() const { return Solved(); }
  // Forgets every sample.
  void Reset();
  const BatchRegressionOptions& options() const { return options_; }
  std::string kind() const { return "batch"; }

 private:
  const BatchRegressionResult& Solved() const;

  int num_parameters_;
  BatchRegressionOptions options_;
  std::vector<double> y_, z_;  // z_: row after row, ρ entries each
  mutable BatchRegressionResult cache_;
  mutable bool solved_ = true;  // cache_ reflects the stored samples
};

}  // namespace ident
