// LcRegression: the log-concave Gaussian filter (ident/observers/lc_gaussian_filter.h) run as a recursive
// regression estimator for log-concave noise — the registry's "lc:laplace", "lc:huber:1.345", "lc:logistic",
// "lc:gengauss:1.5", "lc:gaussian".
//
//   Model:   θ(t+1) = θ(t) (+ w with Cov w = (1/λ − 1)P under forgetting λ),   y(t) = z(t)'θ(t) + σ·u(t),
//            u of a standard log-concave density f (models/noise_density.h) — Henningsson & Åström 2006
//            with the parameters as the state and the regressor as the measurement direction c = z(t).
//   Step:    s = z'θ ~ N(μ, v), μ = z'm, v = z'Pz; the moments of the tilted density f((y − s)/σ)·N(s; μ, v)
//            (LogConcaveNoise::ResidualMoments in units of σ) give the exact Gaussian-projected update
//              m ← m + P z (μ_s − μ)/v,   P ← P − P z z'P (v − v_s)/v²        (LcGaussianFilter::ApplyTilt)
//            O(ρ²) per step plus the one-dimensional moments; no allocation after the start. The filter
//            holds P̃ = P/σ² (the covariance in units of the current noise scale), so a change of the
//            estimated σ rescales all past information alike, as RLS's s²(Z'Z)⁻¹ does.
//   Gaussian f: this is the Kalman filter of the regression model, i.e. recursive least squares with the
//            prior information σ²P(0)⁻¹ (tested to 1e-12 against RLS). Other f: assumed-density filtering,
//            exact for one step; its mean tracks the posterior mean and, as t grows, the MAP/ML estimate
//            (tested against a grid posterior for ρ ≤ 2 and the batch MAP for ρ = 4).
//   Start:   the first W = max(20, 4ρ) samples are kept; then a high-breakdown fit of the window (Cauchy
//            maximum likelihood from elemental subsets, ident/regression/batch_regression.h) gives the centre
//            θ0 and the scale σ = MAD(residuals)/median|u| (the MAD consistency of f), the prior is
//            N(θ0, σ_e²(Z'Z/W)⁻¹) — the information of one average sample, σ_e the noise standard deviation —
//            and the window is replayed. A window whose Z'Z is singular, where one row alone decides a
//            direction (leverage above 0.8, also with the fit's Cauchy weights), where more than half of the
//            rows are fitted exactly (the scale undetermined), or whose Cauchy fit has scale 0 with rows off it
//            (its likelihood unbounded on a hyperplane through repeated rows, e.g. data at rest) waits for
//            the next W samples (up to 5W kept). An explicit scale (LcRegressionOptions::scale) keeps σ
//            fixed; an explicit prior (mean and covariance, with a scale) skips the start.
//            A start from fewer than 5W samples is provisional: its estimate serves (and judges outliers) while
//            the window grows on to 5W samples, and then the start is made again from all of them — the same fit
//            and checks, its θ with the least-squares information of the rows it keeps (residual within five of
//            its scales) as the state, without a replay (Confirm). A few agreeing gross errors can decide a
//            direction that W samples hardly excite (a step input's difference), and a replay from one
//            sample's information can wander on a short, collinear window; five times the rows and the fit's
//            own information do neither. Once per record; no allocation after it.
//   Leverage: a grossly mispredicted sample (relative weight below 0.2) with a regressor coordinate beyond
//            five robust scales of the start window is an error in the regressor (an ARX output outlier
//            carried into later regressors), which the model does not describe, and is not used (weight 0).
//            The start leaves such rows out of its fit.
//   Scale:   after the start, σ follows the median of |ê| (ê = y − μ, the prediction error) by the
//            Robbins–Monro recursion log q ← log q + (2.5/n)(1{|ê| > q} − 1/2) on steps where the parameter
//            uncertainty is below the noise (v < σ²): a bounded step per sample, so an outlier of any size
//            moves σ by the same small amount.
//   Weight:  the report's νβ is f's relative M-estimation weight of the standardised error ê/σ
//            (LogConcaveNoise::Weight): 1 for typical residuals, ln 2·σ/|ê| for a Laplace outlier. The
//            workflow's output cleaning reads it as RLS's and the Kárný–Hangos weights.
//
// Example:
//   ident::LcRegressionOptions o;
//   o.noise = ident::models::LogConcaveNoise::Parse("huber:1.345");
//   ident::LcRegression est(/*num_parameters=*/4, o);
//   for (...) est.Update(y, z);
//   est.parameters(); est.covariance();   // the filter's mean and covariance
#pragma once

#include <optional>
#include <string>

#include <Eigen/Core>

#include "common/step_report.h"
#include "ident/observers/lc_gaussian_filter.h"
#include "models/noise_density.h"

namespace ident {

struct LcRegressionOptions {
  models::LogConcaveNoise noise{models::LogConcaveNoise::Family::kLaplace};
  double scale = 0;                           // σ of u; 0 = estimated (start-up window, then Robbins–Monro)
  int startup_window = 0;                     // W; 0 = max(20, 4ρ)
  double forgetting = 1;                      // λ in (0, 1]
  bool leverage_guard = true;                 // leave out grossly mispredicted samples with outlying regressors (below)
  std::optional<Eigen::VectorXd> prior_mean;  // explicit prior N(m0, P0): both, and a scale
  std::optional<Eigen::MatrixXd> prior_covariance;
};

class LcRegression {
 public:
  // Robust scales beyond which a regressor coordinate is outlying (the start window and the leverage guard).
  static constexpr double kLeverage = 5;

  // Throws InvalidArgument naming the option if `options` is invalid.
  LcRegression(int num_parameters, LcRegressionOptions options);

  // One sample. kRejectedInvalid (state unchanged) for a non-finite sample or a regressor of the wrong
  // size; kNumericalFailure (state unchanged) if the tilted moments underflow. During the start-up the
  // sample is kept and the report carries the prediction of θ = 0.
  StepReport Update(double y, const Eigen::Ref<const Eigen::VectorXd>& z) noexcept;

  int num_parameters() const { return rho_; }
  const Eigen::VectorXd& parameters() const { return started_ ? filter_.mean() : zero_; }
  // The filter's covariance P = σ²P̃ of θ (+inf on the diagonal before the start).
  Eigen::MatrixXd covariance() const;
  double Predict(const Eigen::Ref<const Eigen::VectorXd>& z) const { return z.dot(parameters()); }
  double nu() const { return static_cast<double>(count_); }
  double Dy() const { return noise_std() * noise_std(); }
  double noise_std() const { return sigma_ * noise_sd_; }
  double scale() const { return sigma_; }  // σ of u
  bool in_startup() const { return !started_; }
  bool judges_outliers() const { return true; }
  // The data ended during the start-up: start from every kept sample. False if fewer than ρ + 1 or their
  // Z'Z is singular.
  bool FinishStartup() noexcept;
  void Reset();
  const LcRegressionOptions& options() const { return options_; }

 private:
  StepReport Step(double y, const Eigen::Ref<const Eigen::VectorXd>& z) noexcept;
  // Starts from the kept samples; false if they cannot determine θ. `summarise`: the fit's θ with the
  // information of the rows it keeps is the state, without a replay (Confirm).
  bool Start(bool summarise = false) noexcept;
  // The provisional start's window has grown to 5W samples: starts again from all of them.
  void Confirm() noexcept;
  // Some coordinate of z beyond kLeverage robust scales of the start window (or off a constant column).
  bool Outlying(const Eigen::Ref<const Eigen::VectorXd>& z) const noexcept;

  LcRegressionOptions options_;
  int rho_;
  int window_;
  double noise_sd_;  // standard deviation of u under f
  LcGaussianFilter filter_;
  Eigen::VectorXd zero_;
  Eigen::VectorXd pz_;               // P z (workspace)
  Eigen::VectorXd centre_, spread_;  // median and robust scale of each regressor in the start window
  bool have_window_ = false;         // centre_, spread_ are set (a start from data, not an explicit prior)
  Eigen::MatrixXd kept_;             // (ρ+1) x 5W: y, z of the start-up samples
  long kept_count_ = 0;
  bool started_ = false;
  bool provisional_ = false;  // started from fewer than 5W samples: kept_ grows on to 5W (Confirm)
  long count_ = 0;
  double sigma_ = 0;
  double log_q_ = 0;  // log of the median-|ê| estimate
  long scale_steps_ = 0;
};

}  // namespace ident
