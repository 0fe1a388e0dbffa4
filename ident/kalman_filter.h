// Square-root Kalman filter (array form) with log-likelihood.
//
//   Model:   x(k) = A x(k−1) + B u(k−1) + v,  v ~ N(0, P_N);   y(k) = C x(k) + e,  e ~ N(0, R)
//   Factor:  P = S S' with S lower triangular; the plain covariance update is never formed.
//   Time update:         [A S, P_N^{1/2}] Θ = [S⁺, 0]                     (QR of the transposed pre-array)
//   Measurement update:  [R^{1/2}  C S]  Θ = [Re^{1/2}   0 ]
//                        [  0       S ]      [  K̄       S⁺ ]
//                        x⁺ = x + K̄ Re^{-1/2} (y − C x)
//   Log-likelihood:  log N(y; C x, Re) accumulated over the corrections (prediction-error form).
//   This is the Kalman filter of the log-concave observer [1, sec. IV-A] when everything is Gaussian.
//   Cost O(n³) per step for n states (QR of a 2n × n array); no allocation once the sizes are seen.
//
// Example:
//   auto model = ident::models::MemsAccelerometerDynamics(0.01, 1.0);
//   ident::KalmanFilter kf(Eigen::Vector2d::Zero(), Eigen::Matrix2d::Identity());
//   kf.Predict(model, u);
//   kf.Correct(C, R, y);                          // or kf.Correct(c, r, y) for one scalar reading
//   Eigen::MatrixXd P = kf.covariance();
//
// [1] T. Henningsson, K. J. Åström, "Log-concave Observers", MTNS 2006.
#pragma once

#include <Eigen/Core>
#include <Eigen/QR>

#include "ident/common/step_report.h"
#include "ident/state_observer.h"
#include "models/measurement.h"
#include "models/state_space.h"

namespace ident {

class KalmanFilter {
 public:
  // Throws InvalidArgument if sizes differ, entries are not finite or P0 is not positive definite.
  KalmanFilter(const Eigen::VectorXd& x0, const Eigen::MatrixXd& P0);
  // Convenience for Update(): a fixed model and scalar Gaussian measurement y = c'x + e, e ~ N(0, r).
  KalmanFilter(models::LinearStateSpace model, const models::GaussianMeasurement& measurement,
               const Eigen::VectorXd& x0, const Eigen::MatrixXd& P0);

  // Time update, eqs. (1)-(2) for Gaussians. Rejects a u of the wrong size or non-finite.
  StepReport Predict(const models::LinearStateSpace& model, const Eigen::Ref<const Eigen::VectorXd>& u);
  // Measurement update with p readings. R must be symmetric positive definite (p × p).
  StepReport Correct(const Eigen::Ref<const Eigen::MatrixXd>& C, const Eigen::Ref<const Eigen::MatrixXd>& R,
                     const Eigen::Ref<const Eigen::VectorXd>& y);
  // One scalar reading y = c'x + e, e ~ N(0, r).
  StepReport Correct(const Eigen::Ref<const Eigen::VectorXd>& c, double r, double y);
  // Predict with the stored model, then correct with the stored measurement (second constructor).
  StepReport Update(const StateSpaceItem& item);

  const Eigen::VectorXd& mean() const { return x_; }
  Eigen::MatrixXd covariance() const { return S_ * S_.transpose(); }
  const Eigen::MatrixXd& covariance_factor() const { return S_; }  // S, P = S S'
  double log_likelihood() const { return log_likelihood_; }
  int num_states() const { return static_cast<int>(x_.size()); }

 private:
  Eigen::VectorXd x_;
  Eigen::MatrixXd S_;
  double log_likelihood_ = 0.0;
  // Stored model for Update().
  bool has_model_ = false;
  models::LinearStateSpace model_;
  Eigen::VectorXd c_;
  double r_ = 1.0;
  // Workspaces (resized only when sizes change).
  Eigen::MatrixXd pre_, noise_sqrt_, noise_cached_, r_sqrt_, r_cached_, tmp_;
  Eigen::VectorXd innov_;
  Eigen::HouseholderQR<Eigen::MatrixXd> qr_;
};

}  // namespace ident
