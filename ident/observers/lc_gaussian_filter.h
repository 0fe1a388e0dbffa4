// Log-concave Gaussian filter: a Gaussian filter whose measurement update is the exact mean and
// covariance of f_M(y, x) · N(x; m, P) for a log-concave f_M that depends on x through s = c'x.
//
//   Time update:   m ← A m + B u,  P ← A P A' + P_N                            [1, eqs. (1)-(2)]
//   Measurement:   (Z, μ_s, v_s) = moments of g(y, s) N(s; c'm, σ²), σ² = c'Pc   (models::…::Tilt)
//                  k = P c / σ²,  m ← m + k (μ_s − c'm),  P ← P − k k' (σ² − v_s)   (exact for g(c'x))
//   Log-likelihood: Σ log Z (the predictive probability/density of each reading).
//   Log-concavity of g makes the tilted density unimodal and v_s ≤ σ² (it is in LC(1/σ²), Thm 1 + 2),
//   so P stays positive semidefinite (v_s is clipped to σ² against round-off).
//
// ApplyPairTilt is the same exact update for a reading of a pair s jointly Gaussian with x (the crossing
// wedge of the lagged pair (c'x(k−1), c'x(k)), studies/mems/crossing_reading.h).
//
// On its own, applied at every step, this is the assumed-density filter (moment matching). It is
// exact after one reading but on the MEMS threshold sensor it treats successive, strongly dependent
// y = 0 readings as independent and collapses; see studies/mems/mems_study.h for the event model variants.
//
// Real time: BasicLcGaussianFilter<N> uses Eigen fixed-size types for N ≥ 1 and
// preallocated workspaces for N = Eigen::Dynamic (alias LcGaussianFilter). Predict, Correct, ApplyTilt
// and Update are noexcept and allocate nothing after construction (the closed-form tilts of the
// threshold sensor, quantiser and Gaussian allocate nothing; the quadrature tilts do not either, but
// take ~100× longer); failure is a StepReport status with the state untouched.
// Flops per step for n states, m inputs: Predict 4n³ + 2n² + 2nm (A P A' + P_N, mean);
// Correct 2n² (Pc) + 2n (c'Pc, c'm) + 3n² (mean, rank-one downdate in one pass) + the scalar tilt
// (closed form: two erfc and a few exp/log) ≈ 4n³ + 7n² + 2nm per step (n = 2, m = 1: ≈ 66 flops + tilt).
//
// Example:
//   auto model = ident::models::MemsAccelerometerDynamics(0.01, 1.0);
//   ident::models::ThresholdSensor sensor(Eigen::Vector2d(1, 0), 1.0);
//   ident::BasicLcGaussianFilter<2> f(Eigen::Vector2d::Zero(), Eigen::Matrix2d::Identity());  // or LcGaussianFilter
//   f.Predict(model, u);
//   ident::StepReport r = f.Correct(sensor, y);
//
// [1] T. Henningsson, K. J. Åström, "Log-concave Observers", MTNS 2006.
#pragma once

#include <algorithm>
#include <cmath>
#include <memory>

#include <Eigen/Core>

#include "common/dense_decompositions.h"
#include "common/error.h"
#include "common/step_report.h"
#include "ident/observers/state_observer.h"
#include "models/measurement.h"
#include "models/state_space.h"
#include "models/truncated_bivariate_normal.h"

namespace ident {

template <int N = Eigen::Dynamic>
class BasicLcGaussianFilter {
 public:
  using StateVector = Eigen::Matrix<double, N, 1>;
  using StateMatrix = Eigen::Matrix<double, N, N>;

  // Throws InvalidArgument if sizes differ, entries are not finite or P0 is not positive definite.
  BasicLcGaussianFilter(const Eigen::Ref<const Eigen::VectorXd>& m0, const Eigen::Ref<const Eigen::MatrixXd>& P0);
  // Convenience for Update(): a fixed model and measurement function.
  BasicLcGaussianFilter(models::LinearStateSpace model, std::shared_ptr<const models::ProjectedMeasurement> measurement,
                        const Eigen::Ref<const Eigen::VectorXd>& m0, const Eigen::Ref<const Eigen::MatrixXd>& P0);

  // Eqs. (1)-(2). kRejectedInvalid for a model or u of the wrong size or non-finite u.
  StepReport Predict(const models::LinearStateSpace& model, const Eigen::Ref<const Eigen::VectorXd>& u) noexcept;
  // Exact tilted-moment update. kRejectedInvalid if y is not a possible reading; kNumericalFailure
  // (state unchanged) if the reading has probability 0 to double precision under the prediction.
  StepReport Correct(const models::ProjectedMeasurement& measurement, double y) noexcept;
  // The update for given moments of the tilted density along c (used by event models).
  StepReport ApplyTilt(const Eigen::Ref<const Eigen::VectorXd>& c, const models::TiltedMoments& t) noexcept;
  // ScaleCovariance(factor) followed by ApplyTilt(c, t), in one pass over P and without a copy, for a
  // caller that has formed Pc = P c with P before the scaling (the tilt's prior variance is factor·c'Pc):
  //   k = factor·Pc/σ²,  m ← m + k (μ_s − c'm),  P_ij ← factor·P_ij − (σ² − v_s)·(k_i k_j)
  // (the product k_i k_j is symmetric, so P stays exactly symmetric). Every bound that keeps the result
  // finite is checked first (|P_ij| ≤ trace P for P ≥ 0), so a failure leaves the state untouched.
  StepReport ScaleAndApplyTilt(double factor, const Eigen::Ref<const Eigen::VectorXd>& c,
                               const Eigen::Ref<const Eigen::VectorXd>& Pc, const models::TiltedMoments& t) noexcept;
  // The update for a reading that depends on x only through a pair s jointly Gaussian with x (e.g.
  // s = (c'x(k−1), c'x(k)), studies/mems/crossing_reading.h): `cross` = Cov(x, s) (n × 2), s ~ N(prior_mean,
  // prior_cov) before the reading, `t` the moments of the tilted density of s. x | s is Gaussian, so
  //   K = cross · prior_cov⁻¹,  m ← m + K (μ_t − prior_mean),  P ← P − K (prior_cov − V_t) K'   (exact)
  // prior_cov − V_t ≥ 0 for a log-concave reading [1, Thm 2]; round-off below 0 is clipped.
  StepReport ApplyPairTilt(const Eigen::Ref<const Eigen::MatrixXd>& cross, const Eigen::Vector2d& prior_mean,
                           const Eigen::Matrix2d& prior_cov, const models::TruncatedBivariateMoments& t) noexcept;
  // Replace the state by an externally computed Gaussian, e.g. the marginal of x(k) of the fixed-lag
  // excursion smoother (studies/mems/excursion_reading.h); the log-likelihood is left unchanged.
  // kRejectedInvalid (state untouched) for wrong sizes, non-finite entries or a negative variance; the
  // covariance is symmetrised.
  StepReport Assign(const Eigen::Ref<const Eigen::VectorXd>& mean,
                    const Eigen::Ref<const Eigen::MatrixXd>& cov) noexcept;
  // P ← factor·P, factor ≥ 1: the time update of a random-walk state x(k+1) = x(k) + w with Cov w =
  // (factor − 1)P — exponential forgetting with λ = 1/factor. kRejectedInvalid (state untouched) for a
  // factor below 1 or not finite. O(n²), no allocation.
  StepReport ScaleCovariance(double factor) noexcept {
    if (!(factor >= 1 && std::isfinite(factor))) return {StepStatus::kRejectedInvalid};
    P_ *= factor;
    return {StepStatus::kUpdated};
  }
  // Predict + Correct with the stored model and measurement (the whole step or nothing);
  // kRejectedInvalid without a stored model.
  StepReport Update(const StateSpaceItem& item) noexcept;

  const StateVector& mean() const { return m_; }
  const StateMatrix& covariance() const { return P_; }
  double log_likelihood() const { return log_likelihood_; }
  int num_states() const { return static_cast<int>(m_.size()); }

 private:
  // The commit tail of ApplyPairTilt and Assign: symmetrise P_new_, reject non-finite m_new_/P_new_ (state
  // untouched), else commit them and add log_normalizer to the log-likelihood.
  StepReport CommitUpdate(double log_normalizer, double prediction_error) noexcept;

  StateVector m_, k_, m_new_, m_bak_;
  Eigen::Matrix<double, N, 2> k2_, kd_;
  StateMatrix P_, tmp_, P_new_, P_bak_;
  double log_likelihood_ = 0.0;
  models::LinearStateSpace model_;
  std::shared_ptr<const models::ProjectedMeasurement> measurement_;
};

using LcGaussianFilter = BasicLcGaussianFilter<Eigen::Dynamic>;

// ---------------------------------------------------------------------------------------------------
// Implementation.

template <int N>
BasicLcGaussianFilter<N>::BasicLcGaussianFilter(const Eigen::Ref<const Eigen::VectorXd>& m0,
                                                const Eigen::Ref<const Eigen::MatrixXd>& P0) {
  const auto n = m0.size();
  IDENT_REQUIRE(n >= 1 && m0.allFinite(), "m0 must be a non-empty finite vector");
  IDENT_REQUIRE(N == Eigen::Dynamic || n == N, "m0 has {} entries; this filter has {} states", n, N);
  IDENT_REQUIRE(P0.rows() == n && P0.cols() == n && P0.allFinite(), "P0 is {}×{}; need finite {}×{}", P0.rows(),
                P0.cols(), n, n);
  IDENT_REQUIRE(dense::Llt(P0).info() == Eigen::Success, "P0 is not positive definite");
  m_ = m0;
  P_ = 0.5 * (P0 + P0.transpose());  // exactly symmetric (ScaleAndApplyTilt keeps it so)
  k_.resize(n);
  k2_.resize(n, 2);
  kd_.resize(n, 2);
  m_new_.resize(n);
  m_bak_.resize(n);
  tmp_.resize(n, n);
  P_new_.resize(n, n);
  P_bak_.resize(n, n);
}

template <int N>
BasicLcGaussianFilter<N>::BasicLcGaussianFilter(models::LinearStateSpace model,
                                                std::shared_ptr<const models::ProjectedMeasurement> measurement,
                                                const Eigen::Ref<const Eigen::VectorXd>& m0,
                                                const Eigen::Ref<const Eigen::MatrixXd>& P0)
    : BasicLcGaussianFilter(m0, P0) {
  model.Validate();
  IDENT_REQUIRE(measurement != nullptr, "measurement must not be null");
  IDENT_REQUIRE(model.num_states() == num_states() && measurement->num_states() == num_states(),
                "model ({}) and measurement ({}) must have {} states", model.num_states(), measurement->num_states(),
                num_states());
  model_ = std::move(model);
  measurement_ = std::move(measurement);
}

template <int N>
StepReport BasicLcGaussianFilter<N>::Predict(const models::LinearStateSpace& model,
                                             const Eigen::Ref<const Eigen::VectorXd>& u) noexcept {
  const int n = num_states();
  if (model.A.rows() != n || model.A.cols() != n || model.B.rows() != n || model.process_noise.rows() != n ||
      model.process_noise.cols() != n || u.size() != model.num_inputs() || !u.allFinite()) {
    return {StepStatus::kRejectedInvalid};
  }
  m_new_.noalias() = model.A * m_;  // eq. (1) for the mean
  if (model.num_inputs() > 0) m_new_.noalias() += model.B * u;
  tmp_.noalias() = model.A * P_;
  P_new_.noalias() = tmp_ * model.A.transpose();
  P_new_ += model.process_noise;  // eq. (2): P_N adds
  for (int i = 0; i < n; ++i)     // exactly symmetric, as ScaleAndApplyTilt needs to keep it so
    for (int j = 0; j < i; ++j) P_new_(i, j) = P_new_(j, i) = 0.5 * (P_new_(i, j) + P_new_(j, i));
  if (!m_new_.allFinite() || !P_new_.allFinite()) return {StepStatus::kNumericalFailure};
  m_ = m_new_;
  P_ = P_new_;
  return {StepStatus::kUpdated};
}

template <int N>
StepReport BasicLcGaussianFilter<N>::ApplyTilt(const Eigen::Ref<const Eigen::VectorXd>& c,
                                               const models::TiltedMoments& t) noexcept {
  if (c.size() != num_states() || !c.allFinite()) return {StepStatus::kRejectedInvalid};
  m_new_.noalias() = P_ * c;  // workspace: P c
  return ScaleAndApplyTilt(1.0, c, m_new_, t);
}

template <int N>
StepReport BasicLcGaussianFilter<N>::ScaleAndApplyTilt(double factor, const Eigen::Ref<const Eigen::VectorXd>& c,
                                                       const Eigen::Ref<const Eigen::VectorXd>& Pc,
                                                       const models::TiltedMoments& t) noexcept {
  const int n = num_states();
  if (!(factor >= 1 && std::isfinite(factor)) || c.size() != n || Pc.size() != n || !c.allFinite()) {
    return {StepStatus::kRejectedInvalid};
  }
  if (!t.ok || !std::isfinite(t.mean) || !(t.variance >= 0) || !std::isfinite(t.log_normalizer)) {
    return {StepStatus::kNumericalFailure};
  }
  const double s2 = factor * c.dot(Pc);
  if (!(s2 > 0) || !std::isfinite(s2)) return {StepStatus::kNumericalFailure};
  const double innovation = t.mean - c.dot(m_), shrink = s2 - std::min(t.variance, s2);
  k_.noalias() = (factor / s2) * Pc;
  // Bounds by norms (|x_i| ≤ ‖x‖, max P_ii ≤ trace P for P ≥ 0): finite bounds keep every entry finite.
  const double k2 = k_.squaredNorm();
  if (!std::isfinite(k2) || !std::isfinite(innovation) ||
      !std::isfinite(m_.norm() + std::sqrt(k2) * std::abs(innovation)) ||
      !std::isfinite(factor * P_.trace() + shrink * k2)) {
    return {StepStatus::kNumericalFailure};
  }
  m_.noalias() += innovation * k_;
  for (int j = 0; j < n; ++j) P_.col(j) = factor * P_.col(j) - shrink * (k_ * k_(j));  // entries f·P_ij − s·(k_i k_j)
  log_likelihood_ += t.log_normalizer;
  StepReport report{StepStatus::kUpdated};
  report.prediction_error = innovation;
  return report;
}

template <int N>
StepReport BasicLcGaussianFilter<N>::CommitUpdate(double log_normalizer, double prediction_error) noexcept {
  const int n = num_states();
  for (int i = 0; i < n; ++i) {  // symmetrise against round-off
    for (int j = 0; j < i; ++j) P_new_(i, j) = P_new_(j, i) = 0.5 * (P_new_(i, j) + P_new_(j, i));
  }
  if (!m_new_.allFinite() || !P_new_.allFinite()) return {StepStatus::kNumericalFailure};
  m_ = m_new_;
  P_ = P_new_;
  log_likelihood_ += log_normalizer;
  StepReport report{StepStatus::kUpdated};
  report.prediction_error = prediction_error;
  return report;
}

template <int N>
StepReport BasicLcGaussianFilter<N>::ApplyPairTilt(const Eigen::Ref<const Eigen::MatrixXd>& cross,
                                                   const Eigen::Vector2d& prior_mean, const Eigen::Matrix2d& prior_cov,
                                                   const models::TruncatedBivariateMoments& t) noexcept {
  const int n = num_states();
  if (cross.rows() != n || cross.cols() != 2 || !cross.allFinite() || !prior_mean.allFinite() ||
      !prior_cov.allFinite()) {
    return {StepStatus::kRejectedInvalid};
  }
  if (!t.ok || !t.mean.allFinite() || !t.covariance.allFinite() || !std::isfinite(t.log_probability)) {
    return {StepStatus::kNumericalFailure};
  }
  const double det = prior_cov(0, 0) * prior_cov(1, 1) - prior_cov(0, 1) * prior_cov(1, 0);
  if (!(prior_cov(0, 0) > 0) || !(det > 0)) return {StepStatus::kNumericalFailure};
  Eigen::Matrix2d s_inv;
  s_inv << prior_cov(1, 1), -prior_cov(0, 1), -prior_cov(1, 0), prior_cov(0, 0);
  s_inv /= det;
  k2_.noalias() = cross * s_inv;  // K = Cov(x, s) S⁻¹
  // D = S − V_t ≥ 0 (clip round-off): symmetric 2×2 eigen-decomposition, negative eigenvalues to 0.
  const Eigen::Matrix2d d = 0.5 * ((prior_cov - t.covariance) + (prior_cov - t.covariance).transpose());
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig = dense::SymmetricEigen2x2(d);
  const Eigen::Vector2d lambda = eig.eigenvalues().cwiseMax(0.0);
  const Eigen::Matrix2d d_psd = eig.eigenvectors() * lambda.asDiagonal() * eig.eigenvectors().transpose();
  m_new_ = m_;
  m_new_.noalias() += k2_ * (t.mean - prior_mean);  // m ← m + K (μ_t − μ_s)
  kd_.noalias() = k2_ * d_psd;
  tmp_.noalias() = kd_ * k2_.transpose();
  P_new_ = P_ - tmp_;  // P ← P − K (S − V_t) K'
  return CommitUpdate(t.log_probability, t.mean(1) - prior_mean(1));
}

template <int N>
StepReport BasicLcGaussianFilter<N>::Assign(const Eigen::Ref<const Eigen::VectorXd>& mean,
                                            const Eigen::Ref<const Eigen::MatrixXd>& cov) noexcept {
  const int n = num_states();
  if (mean.size() != n || cov.rows() != n || cov.cols() != n || !mean.allFinite() || !cov.allFinite() ||
      (cov.diagonal().array() < 0).any()) {
    return {StepStatus::kRejectedInvalid};
  }
  m_new_ = mean;
  P_new_ = cov;
  return CommitUpdate(0.0, 0.0);
}

template <int N>
StepReport BasicLcGaussianFilter<N>::Correct(const models::ProjectedMeasurement& measurement, double y) noexcept {
  if (measurement.num_states() != num_states() || !std::isfinite(y)) return {StepStatus::kRejectedInvalid};
  try {  // measurement functions are user-extensible and Boost.Math may throw on overflow
    if (!measurement.IsValidOutput(y)) return {StepStatus::kRejectedInvalid};
    const auto& c = measurement.c();
    m_new_.noalias() = P_ * c;  // workspace: P c
    const double s2 = c.dot(m_new_);
    if (!(s2 > 0) || !std::isfinite(s2)) return {StepStatus::kNumericalFailure};
    return ScaleAndApplyTilt(1.0, c, m_new_, measurement.Tilt(y, c.dot(m_), s2));
  } catch (...) {
    return {StepStatus::kNumericalFailure};
  }
}

template <int N>
StepReport BasicLcGaussianFilter<N>::Update(const StateSpaceItem& item) noexcept {
  if (measurement_ == nullptr) return {StepStatus::kRejectedInvalid};
  m_bak_ = m_;
  P_bak_ = P_;
  const double ll = log_likelihood_;
  const StepReport predicted = Predict(model_, item.u);
  if (!predicted.updated()) return predicted;
  const StepReport corrected = Correct(*measurement_, item.y);
  if (!corrected.updated()) m_ = m_bak_, P_ = P_bak_, log_likelihood_ = ll;  // the whole step or nothing
  return corrected;
}

extern template class BasicLcGaussianFilter<Eigen::Dynamic>;
extern template class BasicLcGaussianFilter<2>;

}  // namespace ident
