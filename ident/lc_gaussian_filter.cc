#include "ident/lc_gaussian_filter.h"

#include <Eigen/Cholesky>

#include "ident/common/error.h"

namespace ident {

LcGaussianFilter::LcGaussianFilter(const Eigen::VectorXd& m0, const Eigen::MatrixXd& P0) : m_(m0), P_(P0) {
  const auto n = m0.size();
  IDENT_REQUIRE(n >= 1 && m0.allFinite(), "m0 must be a non-empty finite vector");
  IDENT_REQUIRE(P0.rows() == n && P0.cols() == n && P0.allFinite(), "P0 is {}×{}; need finite {}×{}", P0.rows(),
                P0.cols(), n, n);
  IDENT_REQUIRE(Eigen::LLT<Eigen::MatrixXd>(P0).info() == Eigen::Success, "P0 is not positive definite");
  k_.resize(n);
  tmp_.resize(n, n);
}

LcGaussianFilter::LcGaussianFilter(models::LinearStateSpace model,
                                   std::shared_ptr<const models::ProjectedMeasurement> measurement,
                                   const Eigen::VectorXd& m0, const Eigen::MatrixXd& P0)
    : LcGaussianFilter(m0, P0) {
  model.Validate();
  IDENT_REQUIRE(measurement != nullptr, "measurement must not be null");
  IDENT_REQUIRE(model.num_states() == num_states() && measurement->num_states() == num_states(),
                "model ({}) and measurement ({}) must have {} states", model.num_states(), measurement->num_states(),
                num_states());
  model_ = std::move(model);
  measurement_ = std::move(measurement);
}

StepReport LcGaussianFilter::Predict(const models::LinearStateSpace& model, const Eigen::Ref<const Eigen::VectorXd>& u) {
  if (model.num_states() != num_states() || u.size() != model.num_inputs() || !u.allFinite()) {
    return {StepStatus::kRejectedInvalid};
  }
  m_ = model.A * m_ + model.B * u;                                   // eq. (1) for the mean
  tmp_.noalias() = model.A * P_;
  P_.noalias() = tmp_ * model.A.transpose();
  P_ += model.process_noise;                                          // eq. (2): P_N adds
  return {StepStatus::kUpdated};
}

StepReport LcGaussianFilter::ApplyTilt(const Eigen::Ref<const Eigen::VectorXd>& c, const models::TiltedMoments& t) {
  if (!t.ok || !std::isfinite(t.mean) || !(t.variance >= 0)) return {StepStatus::kNumericalFailure};
  k_.noalias() = P_ * c;
  const double s2 = c.dot(k_);
  if (!(s2 > 0)) return {StepStatus::kNumericalFailure};
  const double prior_mean = c.dot(m_);
  k_ /= s2;                                                           // k = P c / σ²
  m_ += k_ * (t.mean - prior_mean);                                   // m ← m + k (μ_s − c'm)
  P_.noalias() -= (s2 - std::min(t.variance, s2)) * k_ * k_.transpose();   // P ← P − k k'(σ² − v_s)
  P_ = 0.5 * (P_ + P_.transpose()).eval();
  log_likelihood_ += t.log_normalizer;
  StepReport report{StepStatus::kUpdated};
  report.prediction_error = t.mean - prior_mean;
  return report;
}

StepReport LcGaussianFilter::Correct(const models::ProjectedMeasurement& measurement, double y) {
  if (measurement.num_states() != num_states() || !measurement.IsValidOutput(y)) return {StepStatus::kRejectedInvalid};
  const auto& c = measurement.c();
  const double s2 = c.dot(P_ * c);
  if (!(s2 > 0)) return {StepStatus::kNumericalFailure};
  return ApplyTilt(c, measurement.Tilt(y, c.dot(m_), s2));
}

StepReport LcGaussianFilter::Update(const StateSpaceItem& item) {
  IDENT_REQUIRE(measurement_ != nullptr, "LcGaussianFilter::Update needs the constructor that takes a model");
  const StepReport predicted = Predict(model_, item.u);
  if (!predicted.updated()) return predicted;
  return Correct(*measurement_, item.y);
}

}  // namespace ident
