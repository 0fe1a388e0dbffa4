// Log-concave Gaussian filter: a Gaussian filter whose measurement update is the exact mean and
// covariance of f_M(y, x) · N(x; m, P) for a log-concave f_M that depends on x through s = c'x.
//
//   Time update:   m ← A m + B u,  P ← A P A' + P_N                            [1, eqs. (1)-(2)]
//   Measurement:   (Z, μ_s, v_s) = moments of g(y, s) N(s; c'm, σ²), σ² = c'Pc   (models::…::Tilt)
//                  k = P c / σ²,  m ← m + k (μ_s − c'm),  P ← P − k k' (σ² − v_s)   (exact for g(c'x))
//   Log-likelihood: Σ log Z (the predictive probability/density of each reading).
//   Log-concavity of g makes the tilted density unimodal and v_s ≤ σ² (it is in LC(1/σ²), Thm 1 + 2),
//   so P stays positive semidefinite; we additionally keep P ≥ min_variance · c c' along c.
//
// On its own, applied at every step, this is the assumed-density filter (moment matching). It is
// exact after one reading but on the MEMS threshold sensor it treats successive, strongly dependent
// y = 0 readings as independent and collapses; see ident/mems_study.h for the event model variants.
//
// Example:
//   auto model = ident::models::MemsAccelerometerDynamics(0.01, 1.0);
//   ident::models::ThresholdSensor sensor(Eigen::Vector2d(1, 0), 1.0);
//   ident::LcGaussianFilter f(Eigen::Vector2d::Zero(), Eigen::Matrix2d::Identity());
//   f.Predict(model, u);
//   f.Correct(sensor, y);
//
// [1] T. Henningsson, K. J. Åström, "Log-concave Observers", MTNS 2006.
#pragma once

#include <memory>

#include <Eigen/Core>

#include "ident/common/step_report.h"
#include "ident/state_observer.h"
#include "models/measurement.h"
#include "models/state_space.h"

namespace ident {

class LcGaussianFilter {
 public:
  // Throws InvalidArgument if sizes differ, entries are not finite or P0 is not positive definite.
  LcGaussianFilter(const Eigen::VectorXd& m0, const Eigen::MatrixXd& P0);
  // Convenience for Update(): a fixed model and measurement function.
  LcGaussianFilter(models::LinearStateSpace model, std::shared_ptr<const models::ProjectedMeasurement> measurement,
                   const Eigen::VectorXd& m0, const Eigen::MatrixXd& P0);

  StepReport Predict(const models::LinearStateSpace& model, const Eigen::Ref<const Eigen::VectorXd>& u);
  // Exact tilted-moment update. kRejectedInvalid if y is not a possible reading; kNumericalFailure
  // (state unchanged) if the reading has probability 0 to double precision under the prediction.
  StepReport Correct(const models::ProjectedMeasurement& measurement, double y);
  // The update for given moments of the tilted density along c (used by event models).
  StepReport ApplyTilt(const Eigen::Ref<const Eigen::VectorXd>& c, const models::TiltedMoments& t);
  StepReport Update(const StateSpaceItem& item);

  const Eigen::VectorXd& mean() const { return m_; }
  const Eigen::MatrixXd& covariance() const { return P_; }
  double log_likelihood() const { return log_likelihood_; }
  int num_states() const { return static_cast<int>(m_.size()); }

 private:
  Eigen::VectorXd m_, k_;
  Eigen::MatrixXd P_, tmp_;
  double log_likelihood_ = 0.0;
  models::LinearStateSpace model_;
  std::shared_ptr<const models::ProjectedMeasurement> measurement_;
};

}  // namespace ident
