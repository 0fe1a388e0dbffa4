// Square-root Kalman filter (array form) with log-likelihood; real-time safe, fixed-size or dynamic.
//
//   Model:   x(k) = A x(k−1) + B u(k−1) + v,  v ~ N(0, P_N);   y(k) = C x(k) + e,  e ~ N(0, R)
//   Factor:  P = S S' with S lower triangular; the plain covariance update is never formed.
//   Time update:         [A S, P_N^{1/2}] Θ = [S⁺, 0]                     (QR of the transposed pre-array)
//   Measurement update:  [R^{1/2}  C S]  Θ = [Re^{1/2}   0 ]
//                        [  0       S ]      [  K̄       S⁺ ]
//                        x⁺ = x + K̄ Re^{-1/2} (y − C x)
//   Log-likelihood:  log N(y; C x, Re) accumulated over the corrections (prediction-error form).
//   This is the Kalman filter of the log-concave observer [1, sec. IV-A] when everything is Gaussian.
//
// Real time: BasicKalmanFilter<N> keeps every matrix fixed-size for N ≥ 1 (Eigen fixed-size
// types, no heap at all) and preallocates every workspace for N = Eigen::Dynamic (alias KalmanFilter).
// Predict(), the scalar Correct(c, r, y) and Update() are noexcept and allocate nothing after construction;
// trouble (wrong sizes, NaN/Inf, a non-finite result) is a StepReport status and leaves the state untouched.
// P_N^{1/2} is recomputed (pivoted LDLᵀ, allocation-free) only when P_N changes. The p-reading
// Correct(C, R, y) sizes its workspace the first time it sees p (not for the hot path).
//
// Flops per step for n states, m inputs (Householder QR at 2·rows·cols² − (2/3)·cols³):
//   Predict:          S'A' 2n³, QR of the 2n × n pre-array (10/3)n³, mean 2n² + 2nm   ≈ 5.3 n³ + 2n² + 2nm
//   Correct (scalar): S'c 2n², QR of the (n+1) × (n+1) pre-array (4/3)(n+1)³, gain and mean 4n
//                     ≈ 1.3 (n+1)³ + 2n²
//   (n = 2, m = 1: Predict ≈ 55, Correct ≈ 44 flops, plus a sqrt and a log)
//
// Example:
//   auto model = ident::models::MemsAccelerometerDynamics(0.01, 1.0);
//   ident::BasicKalmanFilter<2> kf(Eigen::Vector2d::Zero(), Eigen::Matrix2d::Identity());   // or KalmanFilter
//   kf.Predict(model, u);
//   ident::StepReport r = kf.Correct(c, /*r=*/0.1, y);  // one scalar reading; r.status says what happened
//   Eigen::Matrix2d P;
//   kf.CovarianceInto(P);                            // no allocation
//
// [1] T. Henningsson, K. J. Åström, "Log-concave Observers", MTNS 2006.
#pragma once

#include <cmath>
#include <numbers>

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include "common/dense_decompositions.h"
#include "common/error.h"
#include "common/step_report.h"
#include "ident/linalg/householder_triangularize.h"
#include "ident/observers/state_observer.h"
#include "models/measurement.h"
#include "models/state_space.h"

namespace ident {

template <int N = Eigen::Dynamic>
class BasicKalmanFilter {
  static constexpr int kTwoN = N == Eigen::Dynamic ? Eigen::Dynamic : 2 * N;
  static constexpr int kN1 = N == Eigen::Dynamic ? Eigen::Dynamic : N + 1;

 public:
  using StateVector = Eigen::Matrix<double, N, 1>;
  using StateMatrix = Eigen::Matrix<double, N, N>;

  // Throws InvalidArgument if sizes differ, entries are not finite or P0 is not positive definite.
  BasicKalmanFilter(const Eigen::Ref<const Eigen::VectorXd>& x0, const Eigen::Ref<const Eigen::MatrixXd>& P0);
  // Convenience for Update(): a fixed model and scalar Gaussian measurement y = c'x + e, e ~ N(0, r).
  BasicKalmanFilter(models::LinearStateSpace model, const models::GaussianMeasurement& measurement,
                    const Eigen::Ref<const Eigen::VectorXd>& x0, const Eigen::Ref<const Eigen::MatrixXd>& P0);

  // Time update, eqs. (1)-(2) for Gaussians. kRejectedInvalid for a model/u of the wrong size or non-finite u.
  StepReport Predict(const models::LinearStateSpace& model, const Eigen::Ref<const Eigen::VectorXd>& u) noexcept;
  // One scalar reading y = c'x + e, e ~ N(0, r), r > 0. prediction_error = normalised innovation.
  StepReport Correct(const Eigen::Ref<const Eigen::VectorXd>& c, double r, double y) noexcept;
  // Measurement update with p readings. R must be symmetric positive definite (p × p). Allocates when p changes.
  StepReport Correct(const Eigen::Ref<const Eigen::MatrixXd>& C, const Eigen::Ref<const Eigen::MatrixXd>& R,
                     const Eigen::Ref<const Eigen::VectorXd>& y);
  // Predict with the stored model, then correct with the stored measurement (second constructor);
  // kRejectedInvalid without a stored model.
  StepReport Update(const StateSpaceItem& item) noexcept;

  const StateVector& mean() const { return x_; }
  StateMatrix covariance() const { return S_ * S_.transpose(); }
  void CovarianceInto(StateMatrix& P) const noexcept { P.noalias() = S_ * S_.transpose(); }
  const StateMatrix& covariance_factor() const { return S_; }  // S, P = S S'
  double log_likelihood() const { return log_likelihood_; }
  int num_states() const { return static_cast<int>(x_.size()); }

 private:
  bool RefreshNoiseSqrt(const Eigen::MatrixXd& process_noise) noexcept;

  StateVector x_, x_new_, x_bak_;
  StateMatrix S_, S_new_, S_bak_;
  double log_likelihood_ = 0.0;
  // Stored model for Update().
  bool has_model_ = false;
  models::LinearStateSpace model_;
  StateVector c_;
  double r_ = 1.0;
  // Workspaces, sized at construction.
  StateMatrix noise_cached_, noise_sqrt_, noise_tmp_;
  Eigen::LDLT<StateMatrix> noise_ldlt_;
  Eigen::Matrix<double, kTwoN, N> pre_;
  Eigen::Matrix<double, kN1, kN1> pre1_, post1_;
  Eigen::Matrix<double, kN1, 1> qr_workspace_;  // TriangularizeInPlace's, n + 1 entries
  // Workspaces of the p-reading Correct (resized when p changes).
  Eigen::MatrixXd pre_p_, post_p_, r_sqrt_, r_cached_;
  Eigen::VectorXd innov_, qr_workspace_p_;
};

using KalmanFilter = BasicKalmanFilter<Eigen::Dynamic>;

// ---------------------------------------------------------------------------------------------------
// Implementation.

template <int N>
BasicKalmanFilter<N>::BasicKalmanFilter(const Eigen::Ref<const Eigen::VectorXd>& x0,
                                        const Eigen::Ref<const Eigen::MatrixXd>& P0) {
  const auto n = x0.size();
  IDENT_REQUIRE(n >= 1 && x0.allFinite(), "x0 must be a non-empty finite vector");
  IDENT_REQUIRE(N == Eigen::Dynamic || n == N, "x0 has {} entries; this filter has {} states", n, N);
  IDENT_REQUIRE(P0.rows() == n && P0.cols() == n && P0.allFinite(), "P0 is {}×{}; need finite {}×{}", P0.rows(),
                P0.cols(), n, n);
  const Eigen::LLT<Eigen::MatrixXd> llt = dense::Llt(0.5 * (P0 + P0.transpose()));
  IDENT_REQUIRE(llt.info() == Eigen::Success, "P0 is not positive definite");
  x_ = x0;
  S_ = llt.matrixL();
  x_new_.resize(n);
  x_bak_.resize(n);
  S_new_.resize(n, n);
  S_bak_.resize(n, n);
  c_ = StateVector::Zero(n);
  noise_cached_ = StateMatrix::Constant(n, n, std::numeric_limits<double>::quiet_NaN());  // never equal: first
  noise_sqrt_.resize(n, n);                                                               // Predict factors P_N
  noise_tmp_.resize(n, n);
  // Sizes the LDLᵀ workspace and sets its status (LDLT(n) leaves the status uninitialised: UBSan).
  noise_ldlt_.compute(StateMatrix::Identity(n, n));
  pre_.resize(2 * n, n);
  pre1_.resize(n + 1, n + 1);
  post1_.resize(n + 1, n + 1);
  qr_workspace_.resize(n + 1);
}

template <int N>
BasicKalmanFilter<N>::BasicKalmanFilter(models::LinearStateSpace model, const models::GaussianMeasurement& measurement,
                                        const Eigen::Ref<const Eigen::VectorXd>& x0,
                                        const Eigen::Ref<const Eigen::MatrixXd>& P0)
    : BasicKalmanFilter(x0, P0) {
  model.Validate();
  IDENT_REQUIRE(model.num_states() == num_states() && measurement.num_states() == num_states(),
                "model ({}) and measurement ({}) must have {} states", model.num_states(), measurement.num_states(),
                num_states());
  model_ = std::move(model);
  c_ = measurement.c();
  r_ = measurement.noise_variance();
  has_model_ = true;
  RefreshNoiseSqrt(model_.process_noise);
}

// F with F F' = P_N from the pivoted factorisation Π P_N Π' = L D L' (P_N may be singular):
// F = Π' L D^{1/2}. Allocation-free: the LDLT and all matrices are sized at construction.
template <int N>
bool BasicKalmanFilter<N>::RefreshNoiseSqrt(const Eigen::MatrixXd& process_noise) noexcept {
  if (noise_cached_ == process_noise) return true;
  if (!process_noise.allFinite()) return false;
  noise_ldlt_.compute(process_noise);
  if (noise_ldlt_.info() != Eigen::Success) return false;
  noise_tmp_ = noise_ldlt_.matrixL();
  const auto& d = noise_ldlt_.vectorD();
  for (int j = 0; j < num_states(); ++j) noise_tmp_.col(j) *= std::sqrt(std::max(d(j), 0.0));
  noise_sqrt_.noalias() = noise_ldlt_.transpositionsP().transpose() * noise_tmp_;
  noise_cached_ = process_noise;
  return true;
}

template <int N>
StepReport BasicKalmanFilter<N>::Predict(const models::LinearStateSpace& model,
                                         const Eigen::Ref<const Eigen::VectorXd>& u) noexcept {
  const int n = num_states();
  if (model.A.rows() != n || model.A.cols() != n || model.B.rows() != n || model.process_noise.rows() != n ||
      model.process_noise.cols() != n || u.size() != model.num_inputs() || !u.allFinite()) {
    return {StepStatus::kRejectedInvalid};
  }
  if (!RefreshNoiseSqrt(model.process_noise)) return {StepStatus::kRejectedInvalid};
  // Transposed pre-array [S'A'; (P_N^{1/2})'] (2n × n); its R factor R satisfies R'R = A P A' + P_N.
  pre_.topRows(n).noalias() = S_.transpose() * model.A.transpose();
  pre_.bottomRows(n) = noise_sqrt_.transpose();
  TriangularizeInPlace(pre_, qr_workspace_);
  S_new_ = pre_.topRows(n).template triangularView<Eigen::Upper>().transpose();
  x_new_.noalias() = model.A * x_;  // eq. (1) for the mean
  if (model.num_inputs() > 0) x_new_.noalias() += model.B * u;
  if (!S_new_.allFinite() || !x_new_.allFinite()) return {StepStatus::kNumericalFailure};
  S_ = S_new_;
  x_ = x_new_;
  return {StepStatus::kUpdated};
}

template <int N>
StepReport BasicKalmanFilter<N>::Correct(const Eigen::Ref<const Eigen::VectorXd>& c, double r, double y) noexcept {
  const int n = num_states();
  if (c.size() != n || !(r > 0) || !std::isfinite(r) || !std::isfinite(y) || !c.allFinite()) {
    return {StepStatus::kRejectedInvalid};
  }
  // Transposed pre-array [[√r, 0], [S'c, S']]; post-array (lower) = [[Re^{1/2}, 0], [K̄, S⁺]].
  pre1_.setZero();
  pre1_(0, 0) = std::sqrt(r);
  pre1_.col(0).tail(n).noalias() = S_.transpose() * c;
  pre1_.bottomRightCorner(n, n) = S_.transpose();
  TriangularizeInPlace(pre1_, qr_workspace_);
  post1_ = pre1_.template triangularView<Eigen::Upper>().transpose();
  const double re_sqrt = post1_(0, 0);
  const double w = (y - c.dot(x_)) / re_sqrt;  // Re^{-1/2} e
  const double log_det = std::log(std::abs(re_sqrt));
  x_new_ = x_ + post1_.col(0).tail(n) * w;
  S_new_ = post1_.bottomRightCorner(n, n);
  if (!std::isfinite(w) || !std::isfinite(log_det) || !x_new_.allFinite() || !S_new_.allFinite()) {
    return {StepStatus::kNumericalFailure};
  }
  x_ = x_new_;
  S_ = S_new_;
  log_likelihood_ += -0.5 * (std::log(2 * std::numbers::pi) + w * w) - log_det;
  StepReport report{StepStatus::kUpdated};
  report.prediction_error = w;
  return report;
}

template <int N>
StepReport BasicKalmanFilter<N>::Correct(const Eigen::Ref<const Eigen::MatrixXd>& C,
                                         const Eigen::Ref<const Eigen::MatrixXd>& R,
                                         const Eigen::Ref<const Eigen::VectorXd>& y) {
  const int n = num_states();
  const auto p = y.size();
  if (C.rows() != p || C.cols() != n || R.rows() != p || R.cols() != p || !y.allFinite() || !C.allFinite()) {
    return {StepStatus::kRejectedInvalid};
  }
  if (p == 1) return Correct(C.row(0).transpose(), R(0, 0), y(0));
  if (r_cached_.rows() != p || r_cached_ != R) {
    const Eigen::LLT<Eigen::MatrixXd> llt = dense::Llt(R);
    if (llt.info() != Eigen::Success) return {StepStatus::kRejectedInvalid};
    r_cached_ = R;
    r_sqrt_ = llt.matrixL();
  }
  // Transposed pre-array [[R^{1/2}', 0], [S'C', S']]; post-array = R_qr' = [[Re^{1/2}, 0], [K̄, S⁺]].
  pre_p_.setZero(p + n, p + n);
  pre_p_.topLeftCorner(p, p) = r_sqrt_.transpose();
  pre_p_.bottomLeftCorner(n, p).noalias() = S_.transpose() * C.transpose();
  pre_p_.bottomRightCorner(n, n) = S_.transpose();
  qr_workspace_p_.resize(p + n);
  TriangularizeInPlace(pre_p_, qr_workspace_p_);
  post_p_ = pre_p_.triangularView<Eigen::Upper>().transpose();  // lower-triangular post-array
  innov_ = y - C * x_;
  const auto re_sqrt = post_p_.topLeftCorner(p, p);
  re_sqrt.triangularView<Eigen::Lower>().solveInPlace(innov_);  // w = Re^{-1/2} e
  double log_det = 0;
  for (int i = 0; i < p; ++i) log_det += std::log(std::abs(re_sqrt(i, i)));
  x_new_ = x_ + post_p_.bottomLeftCorner(n, p) * innov_;
  S_new_ = post_p_.bottomRightCorner(n, n);
  if (!std::isfinite(log_det) || !innov_.allFinite() || !x_new_.allFinite() || !S_new_.allFinite()) {
    return {StepStatus::kNumericalFailure};
  }
  x_ = x_new_;
  S_ = S_new_;
  log_likelihood_ += -0.5 * (p * std::log(2 * std::numbers::pi) + innov_.squaredNorm()) - log_det;
  StepReport report{StepStatus::kUpdated};
  report.prediction_error = std::sqrt(innov_.squaredNorm());
  return report;
}

template <int N>
StepReport BasicKalmanFilter<N>::Update(const StateSpaceItem& item) noexcept {
  if (!has_model_) return {StepStatus::kRejectedInvalid};
  x_bak_ = x_;
  S_bak_ = S_;
  const double ll = log_likelihood_;
  const StepReport predicted = Predict(model_, item.u);
  if (!predicted.updated()) return predicted;
  const StepReport corrected = Correct(c_, r_, item.y);
  if (!corrected.updated()) x_ = x_bak_, S_ = S_bak_, log_likelihood_ = ll;  // the whole step or nothing
  return corrected;
}

extern template class BasicKalmanFilter<Eigen::Dynamic>;
extern template class BasicKalmanFilter<2>;

}  // namespace ident
