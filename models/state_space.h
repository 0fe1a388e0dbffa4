// Linear state-space dynamics with Gaussian process noise (Henningsson & Åström 2006, sec. IV).
//
//   x(k) = A x(k−1) + B u(k−1) + v(k−1),   v ~ N(0, P_N)                       [1, sec. IV]
//
// Time-varying models: keep one LinearStateSpace per step and pass it to the observer's Predict();
// the observers never store a pointer to it. The grid observer also accepts any log-concave noise
// density (ident/observers/grid_observer.h); the Gaussian P_N here is what the Kalman-type filters use.
//
// Example:
//   auto model = ident::models::LinearStateSpace::Make(A, B, P_N);   // validates sizes and P_N ≥ 0
//   Eigen::VectorXd x_next = model.A * x + model.B * u;
//
// [1] T. Henningsson, K. J. Åström, "Log-concave Observers", MTNS 2006.
#pragma once

#include <Eigen/Core>

namespace ident::models {

struct LinearStateSpace {
  Eigen::MatrixXd A;              // n × n
  Eigen::MatrixXd B;              // n × m (m may be 0)
  Eigen::MatrixXd process_noise;  // P_N, n × n, symmetric positive semidefinite

  int num_states() const { return static_cast<int>(A.rows()); }
  int num_inputs() const { return static_cast<int>(B.cols()); }
  // Whether one step of an n-state observer can use this model with input u: A and P_N are n × n, B has n
  // rows, u has num_inputs() finite entries. (The observers' steps return kRejectedInvalid otherwise.)
  bool FitsStep(Eigen::Index n, const Eigen::Ref<const Eigen::VectorXd>& u) const {
    return A.rows() == n && A.cols() == n && B.rows() == n && process_noise.rows() == n && process_noise.cols() == n &&
           u.size() == num_inputs() && u.allFinite();
  }

  // Throws InvalidArgument (naming the matrix) on wrong sizes, non-finite entries or P_N not PSD.
  static LinearStateSpace Make(Eigen::MatrixXd A, Eigen::MatrixXd B, Eigen::MatrixXd process_noise);
  void Validate() const;
};

// The MEMS accelerometer of [1, sec. II]: state (position x1, velocity x2), input = acceleration.
//   A = [1 h; 0 1],  B = [h²/2; h],  P_N = σ² [h³/3 h²/2; h²/2 h]   (σ² = noise intensity)
LinearStateSpace MemsAccelerometerDynamics(double h, double noise_intensity);

}  // namespace ident::models
