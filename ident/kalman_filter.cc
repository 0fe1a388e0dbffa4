#include "ident/kalman_filter.h"

#include <cmath>
#include <numbers>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include "ident/common/error.h"

namespace ident {
namespace {

// A square root F with F F' = M for a symmetric PSD M (eigen-decomposition; M may be singular).
void PsdSquareRoot(const Eigen::MatrixXd& M, Eigen::MatrixXd& F) {
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(M);
  F = eig.eigenvectors() * eig.eigenvalues().cwiseMax(0.0).cwiseSqrt().asDiagonal();
}

}  // namespace

KalmanFilter::KalmanFilter(const Eigen::VectorXd& x0, const Eigen::MatrixXd& P0) : x_(x0) {
  const auto n = x0.size();
  IDENT_REQUIRE(n >= 1 && x0.allFinite(), "x0 must be a non-empty finite vector");
  IDENT_REQUIRE(P0.rows() == n && P0.cols() == n && P0.allFinite(), "P0 is {}×{}; need finite {}×{}", P0.rows(),
                P0.cols(), n, n);
  Eigen::LLT<Eigen::MatrixXd> llt(0.5 * (P0 + P0.transpose()));
  IDENT_REQUIRE(llt.info() == Eigen::Success, "P0 is not positive definite");
  S_ = llt.matrixL();
}

KalmanFilter::KalmanFilter(models::LinearStateSpace model, const models::GaussianMeasurement& measurement,
                           const Eigen::VectorXd& x0, const Eigen::MatrixXd& P0)
    : KalmanFilter(x0, P0) {
  model.Validate();
  IDENT_REQUIRE(model.num_states() == num_states() && measurement.num_states() == num_states(),
                "model ({}) and measurement ({}) must have {} states", model.num_states(), measurement.num_states(),
                num_states());
  model_ = std::move(model);
  c_ = measurement.c();
  r_ = measurement.noise_variance();
  has_model_ = true;
}

StepReport KalmanFilter::Predict(const models::LinearStateSpace& model, const Eigen::Ref<const Eigen::VectorXd>& u) {
  const int n = num_states();
  if (model.num_states() != n || u.size() != model.num_inputs() || !u.allFinite()) {
    return {StepStatus::kRejectedInvalid};
  }
  if (noise_cached_.rows() != n || noise_cached_ != model.process_noise) {  // cache P_N^{1/2}
    noise_cached_ = model.process_noise;
    PsdSquareRoot(noise_cached_, noise_sqrt_);
  }
  // Transposed pre-array [S'A'; (P_N^{1/2})'] (2n × n); its R factor R satisfies R'R = A P A' + P_N.
  pre_.resize(2 * n, n);
  pre_.topRows(n).noalias() = S_.transpose() * model.A.transpose();
  pre_.bottomRows(n) = noise_sqrt_.transpose();
  qr_.compute(pre_);
  S_ = qr_.matrixQR().topRows(n).triangularView<Eigen::Upper>().transpose();
  x_ = model.A * x_ + model.B * u;
  return {StepStatus::kUpdated};
}

StepReport KalmanFilter::Correct(const Eigen::Ref<const Eigen::MatrixXd>& C, const Eigen::Ref<const Eigen::MatrixXd>& R,
                                 const Eigen::Ref<const Eigen::VectorXd>& y) {
  const int n = num_states();
  const auto p = y.size();
  if (C.rows() != p || C.cols() != n || R.rows() != p || R.cols() != p || !y.allFinite() || !C.allFinite()) {
    return {StepStatus::kRejectedInvalid};
  }
  if (r_cached_.rows() != p || r_cached_ != R) {
    r_cached_ = R;
    Eigen::LLT<Eigen::MatrixXd> llt(R);
    if (llt.info() != Eigen::Success) { r_cached_.resize(0, 0); return {StepStatus::kRejectedInvalid}; }
    r_sqrt_ = llt.matrixL();
  }
  // Transposed pre-array [[R^{1/2}', 0], [S'C', S']]; post-array = R_qr' = [[Re^{1/2}, 0], [K̄, S⁺]].
  pre_.setZero(p + n, p + n);
  pre_.topLeftCorner(p, p) = r_sqrt_.transpose();
  pre_.bottomLeftCorner(n, p).noalias() = S_.transpose() * C.transpose();
  pre_.bottomRightCorner(n, n) = S_.transpose();
  qr_.compute(pre_);
  tmp_ = qr_.matrixQR().triangularView<Eigen::Upper>().transpose();  // lower-triangular post-array
  innov_ = y - C * x_;
  const auto re_sqrt = tmp_.topLeftCorner(p, p);
  re_sqrt.triangularView<Eigen::Lower>().solveInPlace(innov_);  // w = Re^{-1/2} e
  double log_det = 0;
  for (int i = 0; i < p; ++i) log_det += std::log(std::abs(re_sqrt(i, i)));
  if (!std::isfinite(log_det) || !innov_.allFinite()) return {StepStatus::kNumericalFailure};
  x_.noalias() += tmp_.bottomLeftCorner(n, p) * innov_;
  S_ = tmp_.bottomRightCorner(n, n);
  const double ll = -0.5 * (p * std::log(2 * std::numbers::pi) + innov_.squaredNorm()) - log_det;
  log_likelihood_ += ll;
  StepReport report{StepStatus::kUpdated};
  report.prediction_error = innov_.size() == 1 ? innov_(0) : std::sqrt(innov_.squaredNorm());
  return report;
}

StepReport KalmanFilter::Correct(const Eigen::Ref<const Eigen::VectorXd>& c, double r, double y) {
  if (c.size() != num_states() || !(r > 0)) return {StepStatus::kRejectedInvalid};
  return Correct(c.transpose(), Eigen::Matrix<double, 1, 1>(r), Eigen::Matrix<double, 1, 1>(y));
}

StepReport KalmanFilter::Update(const StateSpaceItem& item) {
  IDENT_REQUIRE(has_model_, "KalmanFilter::Update needs the constructor that takes a model and measurement");
  const StepReport predicted = Predict(model_, item.u);
  if (!predicted.updated()) return predicted;
  return Correct(c_, r_, item.y);
}

}  // namespace ident
