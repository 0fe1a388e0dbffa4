// Shared fixtures of the observer tests: a stable, lightly coupled 2-state model with one input, and
// linear-Gaussian data from it (y = c'x + e, e ~ N(0, r), input sin(0.3k), seeded); a threshold-sensor
// record of a 2-state model under a ping-pong input (seeded).
#pragma once

#include <cmath>
#include <random>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include "ident/observers/state_observer.h"
#include "models/measurement.h"
#include "models/state_space.h"

namespace ident::testing {

inline models::LinearStateSpace Model2d() {
  Eigen::MatrixXd A(2, 2), B(2, 1), Q(2, 2);
  A << 0.95, 0.2, -0.1, 0.9;
  B << 0.1, 0.5;
  Q << 0.05, 0.01, 0.01, 0.08;
  return models::LinearStateSpace::Make(A, B, Q);
}

// `steps` data items (u(k), y(k)) of x(k) = A x(k−1) + B u(k) + v, v ~ N(0, Q), from x = 0.
inline std::vector<StateSpaceItem> SimulateLinearGaussian(const models::LinearStateSpace& model,
                                                          const Eigen::Vector2d& c, double r, int steps,
                                                          unsigned seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal;
  const Eigen::Matrix2d L = Eigen::LLT<Eigen::Matrix2d>(Eigen::Matrix2d(model.process_noise)).matrixL();
  Eigen::Vector2d x = Eigen::Vector2d::Zero();
  std::vector<StateSpaceItem> items;
  for (int k = 0; k < steps; ++k) {
    const Eigen::VectorXd u = Eigen::VectorXd::Constant(1, std::sin(0.3 * k));
    x = model.A * x + model.B * u + L * Eigen::Vector2d(normal(rng), normal(rng));
    items.push_back({u, c.dot(x) + std::sqrt(r) * normal(rng)});
  }
  return items;
}

// `steps` readings y(k) = sensor(x(k)) of a 2-state model (the MEMS accelerometer: position, velocity)
// from x = (0, 2), with a ping-pong input: after an event push back, else track velocity ∓4.
inline std::vector<StateSpaceItem> SimulateThresholdSensor(const models::LinearStateSpace& model,
                                                           const models::ThresholdSensor& sensor, int steps,
                                                           unsigned seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal;
  const Eigen::Matrix2d L = Eigen::LLT<Eigen::Matrix2d>(Eigen::Matrix2d(model.process_noise)).matrixL();
  Eigen::Vector2d x(0, 2);
  std::vector<StateSpaceItem> items;
  double u = 0, dir = 1;
  for (int k = 0; k < steps; ++k) {
    x = model.A * x + model.B * u + L * Eigen::Vector2d(normal(rng), normal(rng));
    const double y = sensor.Measure(x);
    items.push_back({Eigen::VectorXd::Constant(1, u), y});
    if (y != 0) dir = -y;
    u = y != 0 ? -y * 32 : -(x(1) - dir * 4) / 0.125;
  }
  return items;
}

}  // namespace ident::testing
