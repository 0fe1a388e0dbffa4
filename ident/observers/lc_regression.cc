#include "ident/observers/lc_regression.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "common/dense_decompositions.h"
#include "common/error.h"
#include "ident/regression/batch_regression.h"
#include "ident/regression/regression_prior.h"

namespace ident {
namespace {

constexpr double kLcInfinity = std::numeric_limits<double>::infinity();
// Robbins–Monro gain for log q, ≈ 1/(q·f_|ê|(q)) at the median for the families of models/noise_density.h.
constexpr double kScaleGain = 2.5;
// The start waits while a row of its window has a leverage above this.
constexpr double kMaxStartLeverage = 0.8;
// The start's fit counts a row as a gross error beyond this many of its scales (Cauchy weight below 1/26).
constexpr double kGrossResidual = 5;
// A relative weight below this is a gross error (the workflow's output cleaning threshold).
constexpr double kGrossWeight = 0.2;

// A regressor's robust scale for the leverage test: the larger of the MAD scale and the central 80 %'s
// half-width in normal units, (q90 − q10)/2.5631 (both σ for Gaussian data). The MAD alone is the noise
// around one level of a two-level input (a PRBS or step test signal), which would make every sample at the
// other level a far-out regressor; the deciles see both levels and still ignore up to 10 % gross errors.
double LeverageScale(const Eigen::VectorXd& column) {
  const Eigen::Index n = column.size();
  if (n == 0) return 0;
  std::vector<double> v(column.data(), column.data() + n);
  const auto lo = v.begin() + n / 10, hi = v.begin() + (9 * n) / 10;
  std::nth_element(v.begin(), lo, v.end());
  const double q10 = *lo;
  std::nth_element(lo, hi, v.end());
  const double q90 = *hi;
  return std::max(MadScale(column), (q90 - q10) / 2.5631031310892007);
}

// With the fit's Cauchy weights w = 1/(1 + r²), r the residuals in units of its scale: rows the fit treats
// as outliers do not determine a direction, so one inlier alone must not either. False if some weighted
// leverage w_i z_i'(Z'WZ)⁻¹z_i exceeds kMaxStartLeverage or Z'WZ is numerically singular.
bool WeightedLeverageBounded(const Eigen::MatrixXd& Z, const Eigen::VectorXd& r) {
  const Eigen::VectorXd w = (1 / (1 + r.array().square())).matrix();
  const Eigen::LDLT<Eigen::MatrixXd> weighted = dense::Ldlt(Z.transpose() * w.asDiagonal() * Z);
  if (weighted.info() != Eigen::Success || !(weighted.vectorD().minCoeff() > 1e-12 * weighted.vectorD().maxCoeff()))
    return false;
  const Eigen::MatrixXd Hw = weighted.solve(Z.transpose());
  for (Eigen::Index i = 0; i < Z.rows(); ++i)
    if (w(i) * Z.row(i).dot(Hw.col(i)) > kMaxStartLeverage) return false;
  return true;
}

// (Σ zz')⁻¹ over the rows the fit keeps (residual within kGrossResidual of its scale; every row at scale 0):
// their least-squares information, which f's Fisher information only exceeds (Cramér–Rao). NaN if singular.
Eigen::MatrixXd KeptRowsCovariance(const Eigen::MatrixXd& Z, const Eigen::VectorXd& residuals, double scale) {
  const Eigen::Index rho = Z.cols();
  Eigen::MatrixXd information = Eigen::MatrixXd::Zero(rho, rho);
  for (Eigen::Index i = 0; i < Z.rows(); ++i)
    if (!(scale > 0) || std::abs(residuals(i)) <= kGrossResidual * scale)
      information.selfadjointView<Eigen::Lower>().rankUpdate(Z.row(i).transpose());
  const Eigen::LLT<Eigen::MatrixXd> llt = dense::Llt(information.selfadjointView<Eigen::Lower>());
  if (llt.info() != Eigen::Success) return Eigen::MatrixXd::Constant(rho, rho, std::nan(""));
  return dense::Inverse(llt);
}

LcRegressionOptions CheckedLcOptions(int rho, LcRegressionOptions o) {
  IDENT_REQUIRE(rho >= 1, "lc regression: num_parameters = {}; need >= 1", rho);
  IDENT_REQUIRE(o.scale == 0 || (std::isfinite(o.scale) && o.scale > 0),
                "lc regression: scale = {}; need > 0 (or 0: estimated)", o.scale);
  IDENT_REQUIRE(o.startup_window == 0 || o.startup_window >= rho + 1,
                "lc regression: startup window = {}; need 0 (automatic) or at least ρ + 1 = {}", o.startup_window,
                rho + 1);
  IDENT_REQUIRE(std::isfinite(o.forgetting) && o.forgetting > 0 && o.forgetting <= 1,
                "lc regression: forgetting = {}; need 0 < λ <= 1", o.forgetting);
  IDENT_REQUIRE(o.prior_mean.has_value() == o.prior_covariance.has_value(),
                "lc regression: an explicit prior needs both its mean and its covariance");
  if (o.prior_mean) {
    IDENT_REQUIRE(o.scale > 0, "lc regression: an explicit prior needs an explicit scale");
    IDENT_REQUIRE(o.prior_mean->size() == rho && o.prior_mean->allFinite(),
                  "lc regression: prior mean has {} entries; need {} finite", o.prior_mean->size(), rho);
  }
  return o;
}

}  // namespace

LcRegression::LcRegression(int num_parameters, LcRegressionOptions options)
    : options_(CheckedLcOptions(num_parameters, std::move(options))),
      rho_(num_parameters),
      window_(options_.startup_window > 0 ? options_.startup_window : std::max(20, 4 * num_parameters)),
      noise_sd_(options_.noise.standard_deviation()),
      filter_(options_.prior_mean ? *options_.prior_mean : Eigen::VectorXd::Zero(num_parameters),
              options_.prior_covariance ? *options_.prior_covariance
                                        : Eigen::MatrixXd::Identity(num_parameters, num_parameters)),
      zero_(Eigen::VectorXd::Zero(num_parameters)),
      pz_(num_parameters),
      centre_(Eigen::VectorXd::Zero(num_parameters)),
      spread_(Eigen::VectorXd::Zero(num_parameters)),
      kept_(num_parameters + 1, 5L * window_) {
  Reset();
}

void LcRegression::Reset() {
  kept_count_ = 0;
  provisional_ = false;
  count_ = 0;
  scale_steps_ = 0;
  sigma_ = options_.scale;
  log_q_ = sigma_ > 0 ? std::log(sigma_ * options_.noise.median_abs()) : 0;
  have_window_ = false;
  started_ = options_.prior_mean.has_value();
  if (started_) filter_.Assign(*options_.prior_mean, *options_.prior_covariance / (sigma_ * sigma_));
}

Eigen::MatrixXd LcRegression::covariance() const {
  if (started_) return sigma_ * sigma_ * filter_.covariance();
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(rho_, rho_);
  out.diagonal().setConstant(kLcInfinity);
  return out;
}

StepReport LcRegression::Update(double y, const Eigen::Ref<const Eigen::VectorXd>& z) noexcept {
  if (z.size() != rho_ || !std::isfinite(y) || !z.allFinite()) return {StepStatus::kRejectedInvalid};
  if (started_) {
    StepReport report = Step(y, z);
    if (report.updated()) ++count_, report.nu = static_cast<double>(count_), report.weight /= report.nu;
    if (provisional_) {  // the window grows on to 5W samples, then the start is made again from all of them
      kept_(0, kept_count_) = y;
      kept_.col(kept_count_).tail(rho_) = z;
      if (++kept_count_ == kept_.cols()) Confirm();
    }
    return report;
  }
  // Start-up: keep the sample (the oldest is dropped once 5W are kept and none of their windows started).
  if (kept_count_ == kept_.cols()) {
    kept_.leftCols(kept_.cols() - 1) = kept_.rightCols(kept_.cols() - 1).eval();
    --kept_count_;
  }
  kept_(0, kept_count_) = y;
  kept_.col(kept_count_).tail(rho_) = z;
  ++kept_count_;
  ++count_;
  StepReport report{StepStatus::kUpdated};
  report.prediction_error = y;
  report.nu = static_cast<double>(count_);
  if (count_ % window_ == 0) Start();
  return report;
}

void LcRegression::Confirm() noexcept {
  // The start again, from the 5W samples kept since the start-up began (the provisional window included):
  // the same robust fit and checks on five times the rows in every direction, its θ with the information of
  // the rows it keeps as the state (Start's `summarise`). If these samples fail the checks, the provisional
  // start stands.
  const Eigen::VectorXd centre = centre_, spread = spread_;
  const double sigma = sigma_, log_q = log_q_;
  const long count = count_, scale_steps = scale_steps_;
  provisional_ = false;
  if (!Start(/*summarise=*/true)) {
    centre_ = centre, spread_ = spread, have_window_ = true;
    sigma_ = sigma, log_q_ = log_q, count_ = count, scale_steps_ = scale_steps;
  }
  kept_count_ = 0;
}

bool LcRegression::FinishStartup() noexcept {
  if (started_ || kept_count_ < rho_ + 1) return false;
  return Start();
}

bool LcRegression::Start(bool summarise) noexcept {
  try {
    const long n = std::min<long>(kept_count_, 5L * window_);
    const Eigen::VectorXd Yall = kept_.block(0, kept_count_ - n, 1, n).transpose();
    const Eigen::MatrixXd Zall = kept_.block(1, kept_count_ - n, rho_, n).transpose();
    // Each regressor's median and robust scale (LeverageScale) in the window; rows with a coordinate beyond
    // kLeverage scales are left out of the fit and of the prior's information (they would carry it alone).
    for (int j = 0; j < rho_; ++j) {
      const Eigen::VectorXd column = Zall.col(j);
      Eigen::VectorXd sorted = column;
      std::nth_element(sorted.data(), sorted.data() + n / 2, sorted.data() + n);
      centre_(j) = sorted(n / 2);
      spread_(j) = LeverageScale(column);
    }
    have_window_ = true;
    std::vector<Eigen::Index> inliers;
    for (Eigen::Index i = 0; i < n; ++i)
      if (!Outlying(Zall.row(i).transpose())) inliers.push_back(i);
    if (static_cast<long>(inliers.size()) < rho_ + 1) return have_window_ = false;
    const Eigen::VectorXd Y = Yall(inliers);
    const Eigen::MatrixXd Z = Zall(inliers, Eigen::all);
    const Eigen::MatrixXd ZtZ = Z.transpose() * Z;
    const Eigen::LDLT<Eigen::MatrixXd> ldlt = dense::Ldlt(ZtZ / static_cast<double>(Z.rows()));
    if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().minCoeff() > 1e-12 * ldlt.vectorD().maxCoeff()))
      return have_window_ = false;
    // One row alone deciding a direction (leverage z'(Z'Z)⁻¹z above 0.8) would set it to that row's value,
    // outlier or not: wait for more samples.
    const Eigen::MatrixXd H = ldlt.solve(Z.transpose()) / static_cast<double>(Z.rows());
    for (Eigen::Index i = 0; i < Z.rows(); ++i)
      if (Z.row(i).dot(H.col(i)) > kMaxStartLeverage) return have_window_ = false;
    const BatchRegressionResult fit = CauchyMlRegression(Z, Y);
    if (!fit.theta.allFinite()) return have_window_ = false;
    // Rows on the fit's hyperplane (to rounding). A Cauchy scale of 0 with rows off it: the likelihood is
    // unbounded on a hyperplane through half of the window or more (e.g. the repeated rows of a constant
    // stretch, the data at rest), which leaves θ undetermined off those rows: wait for more samples.
    const Eigen::VectorXd residuals = Y - Z * fit.theta;
    long exact = 0;
    for (Eigen::Index i = 0; i < Z.rows(); ++i)
      exact += std::abs(residuals(i)) <= 1e-9 * (std::abs(Y(i)) + Z.row(i).cwiseAbs().dot(fit.theta.cwiseAbs()));
    if (!(fit.scale > 0) && exact < Z.rows()) return have_window_ = false;
    if (fit.scale > 0 && !WeightedLeverageBounded(Z, residuals / fit.scale)) return have_window_ = false;
    if (options_.scale == 0) {
      // More than half of the rows fitted exactly (a quantised or constant stretch of output) leave the
      // noise scale undetermined: wait for more samples.
      if (2 * exact > Z.rows()) return have_window_ = false;
      // MadScale = 1.4826·MAD; MAD/median|u| is σ of f.
      const double mad = MadScale(residuals) / 1.482602218505602;
      if (!(mad > 0 && std::isfinite(mad))) return have_window_ = false;
      sigma_ = mad / options_.noise.median_abs();
      log_q_ = std::log(mad);
    }
    const double sd = options_.noise.standard_deviation();
    if (summarise) {
      // The fit summarises the window: P̃ = sd_f²·(Σ zz')⁻¹ over the rows it keeps, no replay.
      const Eigen::MatrixXd P0 = sd * sd * KeptRowsCovariance(Z, residuals, fit.scale);
      if (!P0.allFinite() || filter_.Assign(fit.theta, P0).status != StepStatus::kUpdated) return false;
      scale_steps_ = n;  // σ is the window's: the Robbins–Monro gain continues as after n steps
      return true;
    }
    // P̃(0) = P(0)/σ² = sd_f²·(Z'Z/n)⁻¹: one average sample's least-squares information.
    const Eigen::MatrixXd P0 = sd * sd * ldlt.solve(Eigen::MatrixXd::Identity(rho_, rho_));
    if (!P0.allFinite() || filter_.Assign(fit.theta, P0).status != StepStatus::kUpdated) return false;
    started_ = true;
    // Replay the kept samples (the oldest first) through the filter.
    count_ = 0;
    scale_steps_ = 0;
    for (long i = kept_count_ - n; i < kept_count_; ++i) {
      const StepReport r = Step(kept_(0, i), kept_.col(i).tail(rho_));
      if (r.updated()) ++count_;
    }
    // A start from fewer than 5W samples is provisional (Confirm); the window keeps growing.
    provisional_ = n < kept_.cols();
    if (!provisional_) kept_count_ = 0;
    return true;
  } catch (...) {
    return false;
  }
}

bool LcRegression::Outlying(const Eigen::Ref<const Eigen::VectorXd>& z) const noexcept {
  if (!have_window_) return false;
  for (int j = 0; j < rho_; ++j) {
    const double d = std::abs(z(j) - centre_(j));
    if (spread_(j) > 0 ? d > kLeverage * spread_(j) : d > 0) return true;
  }
  return false;
}

StepReport LcRegression::Step(double y, const Eigen::Ref<const Eigen::VectorXd>& z) noexcept {
  // The random-walk time update P̃ ← P̃/λ (forgetting) goes into the measurement update (ScaleAndApplyTilt).
  const double factor = options_.forgetting < 1 ? 1 / options_.forgetting : 1;
  const double mu = z.dot(filter_.mean());
  pz_.noalias() = filter_.covariance() * z;
  const double vt = factor * z.dot(pz_);  // ṽ = z'P̃z = Var(z'θ)/σ² after the time update
  const double e = y - mu;
  if (!(vt > 0 && std::isfinite(vt))) {
    // z carries no information on θ (z = 0): nothing to learn, the sample counts.
    filter_.ScaleCovariance(factor);
    StepReport report{StepStatus::kUpdated};
    report.prediction_error = e;
    report.weight = options_.noise.Weight(e / sigma_);
    return report;
  }
  const double a = e / sigma_;
  // Leverage guard: a grossly mispredicted sample with a regressor coordinate beyond kLeverage robust
  // scales of the start window is read as an error in the regressor (an ARX output outlier carried into
  // later regressors), which the model y = z'θ + σu does not describe: it is not used. (A test on the
  // Mahalanobis radius in the information so far would also refuse, for ever, the samples that have to
  // correct a direction the start window hardly determined.)
  const double weight = options_.noise.Weight(a);
  if (options_.leverage_guard && weight < kGrossWeight && Outlying(z)) {
    filter_.ScaleCovariance(factor);
    StepReport report{StepStatus::kUpdated};
    report.prediction_error = e;
    report.weight = 0;
    return report;
  }
  const models::TiltedMoments r = options_.noise.ResidualMoments(a, vt);
  if (!r.ok) return {StepStatus::kNumericalFailure};
  // s = y − σr: mean μ + σ(a − E r); the filter holds P̃, so the variance goes in units of σ² (Var r).
  const models::TiltedMoments s{r.log_normalizer - std::log(sigma_), mu + sigma_ * (a - r.mean), r.variance, true};
  StepReport report = filter_.ScaleAndApplyTilt(factor, z, pz_, s);
  if (!report.updated()) return report;
  report.prediction_error = e;
  report.weight = weight;
  if (options_.scale == 0 && vt < 1) {
    ++scale_steps_;
    log_q_ += kScaleGain / static_cast<double>(scale_steps_ + window_) * (std::abs(e) > std::exp(log_q_) ? 0.5 : -0.5);
    sigma_ = std::exp(log_q_) / options_.noise.median_abs();
  }
  return report;
}

}  // namespace ident
