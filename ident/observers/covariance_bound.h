// Certified covariance bound tracker (Henningsson & Åström 2006, Theorems 1 and 2).
//
// Propagates the strength P̄ of log-concavity of the Bayesian observer's density f_k ∈ LC(P̄⁻¹):
//   dynamics (1)        P̄ ← A P̄ A'                         Thm 1, affine map
//   process noise (2)   P̄ ← P̄ + P_N                        Thm 1, convolution (Gaussian f_N ∈ LC(P_N⁻¹))
//   measurement (3)     P̄ ← (P̄⁻¹ + Q(y))⁻¹                 Thm 1, product with f_M(y, ·) ∈ LC(Q(y))
// and by Theorem 2 the observer's covariance is ≤ P̄ at every step (a certified upper bound), provided
// the prior is in LC(P̄0⁻¹) (e.g. Gaussian with covariance ≤ P̄0).
//
// With exact MEMS threshold readings Q(y) = 0 and the bound ignores the measurements (it grows
// cubically). The paper's modified event measurement [1, sec. V-A] treats the first reading past the
// threshold as a Gaussian reading of x1 with variance σ_M² (Q_M = diag(σ_M⁻², 0)) and y = 0 as LC(0);
// UpdateStrength() takes such a Q directly. That bound is approximate (it holds for the modified model).
//
// Example:
//   ident::CovarianceBoundTracker bound(P0);
//   bound.Predict(model);                      // A P̄ A' + P_N
//   bound.Correct(sensor, y);                  // Q(y) = sensor.Strength(y)
//   Eigen::MatrixXd Pbar = bound.covariance();
//
// [1] T. Henningsson, K. J. Åström, "Log-concave Observers", MTNS 2006.
#pragma once

#include <Eigen/Core>

#include "approx/strong_log_concavity.h"
#include "common/step_report.h"
#include "models/measurement.h"
#include "models/state_space.h"

namespace ident {

class CovarianceBoundTracker {
 public:
  explicit CovarianceBoundTracker(const Eigen::MatrixXd& P0) : bound_(P0) {}

  StepReport Predict(const models::LinearStateSpace& model) {
    if (model.num_states() != bound_.dim()) return {StepStatus::kRejectedInvalid};
    bound_.Affine(model.A);                // Thm 1, affine
    bound_.Convolve(model.process_noise);  // Thm 1, convolution
    return {StepStatus::kUpdated};
  }
  StepReport Correct(const models::MeasurementFunction& measurement, double y) {
    if (measurement.num_states() != bound_.dim() || !measurement.IsValidOutput(y))
      return {StepStatus::kRejectedInvalid};
    bound_.Multiply(measurement.Strength(y));  // Thm 1, product
    return {StepStatus::kUpdated};
  }
  // Product with a function in LC(Q) given directly (e.g. the modified event measurement).
  StepReport UpdateStrength(const Eigen::Ref<const Eigen::MatrixXd>& Q) {
    bound_.Multiply(Q);
    return {StepStatus::kUpdated};
  }
  // Rank-one strength q c c' (cheaper than UpdateStrength).
  StepReport UpdateStrength(const Eigen::Ref<const Eigen::VectorXd>& c, double q) {
    bound_.MultiplyRankOne(c, q);
    return {StepStatus::kUpdated};
  }
  const Eigen::MatrixXd& covariance() const { return bound_.P(); }

 private:
  approx::LcBound bound_;
};

}  // namespace ident
