// A MAP-smoothing problem whose states grow far beyond its residuals, for the smoother's tests
// (certified_gap_test.cc, map_smoother_fast_path_test.cc).
#pragma once

#include <random>

#include <Eigen/Core>

#include "ident/smoothing/map_smoother.h"
#include "models/penalties.h"

namespace ident::duality_test {

// x_{t+1} = [[1, 1], [0, 1]] x_t + w_t (unit covariance), z_t = x_{t,1} + Laplace noise: positions ~ T^1.5.
inline MapSmootherProblem DoubleIntegrator(int T, const models::Penalty& measurement, unsigned seed = 5) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> N(0, 1);
  std::exponential_distribution<double> E(1);
  MapSmootherProblem p;
  p.F = {(Eigen::MatrixXd(2, 2) << 1, 1, 0, 1).finished()};
  p.H = {(Eigen::MatrixXd(1, 2) << 1, 0).finished()};
  p.process = {models::Penalty::Quadratic(Eigen::MatrixXd::Identity(2, 2))};
  p.measurement = {measurement};
  p.z.resize(1, T + 1);
  double position = 0, velocity = 0;
  for (int t = 0; t <= T; ++t) {
    velocity += N(rng);
    position += velocity;
    p.z(0, t) = position + (rng() % 2 ? 1 : -1) * E(rng);
  }
  return p;
}

}  // namespace ident::duality_test
