#include "ident/regression/batch_regression.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <numeric>
#include <random>
#include <utility>

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <Eigen/QR>

#include "common/error.h"
#include "ident/regression/internal/batch_regression_common.h"

namespace ident {

std::string HuberOptions::Validate() const {
  if (!(k > 0) || !std::isfinite(k)) return fmt::format("huber k = {}; need a finite k > 0", k);
  if (!(tolerance >= 0)) return fmt::format("huber tolerance = {}; need tolerance >= 0", tolerance);
  if (max_iterations < 1) return fmt::format("huber max_iterations = {}; need >= 1", max_iterations);
  return "";
}

BatchRegressionResult HuberRegression(const Eigen::Ref<const Eigen::MatrixXd>& Z,
                                      const Eigen::Ref<const Eigen::VectorXd>& y, const HuberOptions& options) {
  using namespace batch_regression_detail;
  const std::string error = options.Validate();
  IDENT_REQUIRE(error.empty(), "{}", error);
  RequireRegressionData(Z, y);
  const Orthonormalised f = RequireFullRank(Z);
  const Eigen::Index n = Z.rows(), p = Z.cols();
  const double k = options.k;

  BatchRegressionResult result;
  result.starts = 1;
  Eigen::VectorXd beta = f.Q.transpose() * y;  // least squares
  Eigen::VectorXd r = y - f.Q * beta;
  double s = 0;
  // The iterations' n-row vectors and n×p matrix, sized once.
  Eigen::VectorXd w(n), next(n);
  Eigen::MatrixXd Qw(n, p);
  std::vector<double> sorted;
  while (result.iterations < options.max_iterations) {
    s = MedianAbs(r, sorted) / 0.6745;
    if (!(s > 0)) {  // more than half the residuals vanish: an exact fit (rlm stops here too)
      result.converged = true;
      break;
    }
    w = (k * s / r.array().abs()).min(1.0);
    if (!WeightedFit(f.Q, y, w, beta, Qw)) break;
    next.noalias() = y - f.Q * beta;
    ++result.iterations;
    // rlm's relative change of the residuals, without its absolute floor max(1e-20, ‖r‖²), which stops the
    // iteration at once on data in small units (‖r‖² > 0 here: the MAD scale s is positive); relative to
    // √n·s where that is smaller, so that a gross error, which dominates ‖r‖, does not hide the change of
    // the other residuals. Norms without overflow: a residual of 1e200 squares to infinity.
    const double delta = (next - r).stableNorm() / std::min(r.stableNorm(), std::sqrt(static_cast<double>(n)) * s);
    r.swap(next);
    if (delta <= options.tolerance) {
      result.converged = true;
      break;
    }
  }
  result.theta = f.T * beta;
  result.scale = s;
  const Eigen::MatrixXd unscaled = f.T * f.T.transpose();  // (Z'Z)⁻¹
  if (!(s > 0)) {
    result.covariance = Eigen::MatrixXd::Zero(p, p);
    return result;
  }
  const Eigen::ArrayXd u = r.array() / s;
  const Eigen::ArrayXd psi = u.max(-k).min(k);
  const Eigen::ArrayXd dpsi = (u.abs() <= k).cast<double>();
  const double nd = static_cast<double>(n);
  const double mean = dpsi.mean();
  const double var = (dpsi - mean).square().sum() / (nd - 1);
  const double kappa = 1 + static_cast<double>(p) * var / (nd * mean * mean);
  const double S = s * s * psi.square().sum() / static_cast<double>(n - p);
  result.covariance = (kappa * kappa / (mean * mean) * S) * unscaled;
  result.objective = (u.abs() <= k).select(0.5 * u.square(), k * u.abs() - 0.5 * k * k).sum();
  return result;
}

// ---- BatchRegressionEstimator ----------------------------------------------------------------------------

namespace batch_regression_detail {
namespace {
BatchRegressionResult Unsolved(int p) {
  BatchRegressionResult r;
  r.theta = Eigen::VectorXd::Zero(p);
  r.scale = kNaN;
  r.covariance = Eigen::MatrixXd::Constant(p, p, kInf);
  r.objective = kNaN;
  return r;
}

const BatchRegressionOptions& CheckedOptions(int num_parameters, const BatchRegressionOptions& options) {
  IDENT_REQUIRE(num_parameters >= 1, "num_parameters = {}; need >= 1", num_parameters);
  const std::string error =
      options.method == BatchMethod::kHuber ? options.huber.Validate() : options.cauchy.Validate();
  IDENT_REQUIRE(error.empty(), "{}", error);
  return options;
}
}  // namespace
}  // namespace batch_regression_detail

BatchRegressionEstimator::BatchRegressionEstimator(int num_parameters, const BatchRegressionOptions& options)
    : num_parameters_(num_parameters),
      options_(batch_regression_detail::CheckedOptions(num_parameters, options)),
      cache_(batch_regression_detail::Unsolved(num_parameters)) {}

void BatchRegressionEstimator::Reset() {
  y_.clear();
  z_.clear();
  cache_ = batch_regression_detail::Unsolved(num_parameters_);
  solved_ = true;
}

const BatchRegressionResult& BatchRegressionEstimator::Solved() const {
  if (solved_) return cache_;
  solved_ = true;
  const Eigen::Index n = static_cast<Eigen::Index>(y_.size()), p = num_parameters_;
  const Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> Zrows(z_.data(), n, p);
  const Eigen::MatrixXd Z = Zrows;
  const Eigen::Map<const Eigen::VectorXd> y(y_.data(), n);
  if (n <= p || batch_regression_detail::Orthonormalise(Z).rank < p) {
    cache_ = batch_regression_detail::Unsolved(num_parameters_);
  } else if (options_.method == BatchMethod::kHuber) {
    cache_ = HuberRegression(Z, y, options_.huber);
  } else {
    cache_ = CauchyMlRegression(Z, y, options_.cauchy);
  }
  return cache_;
}

}  // namespace ident
