// MapSmootherOptions::on_iteration (the progress of `ident smooth`): one call per interior-point iteration,
// 0 … iterations, the last with the result's KKT residual, on both the fused fast path and the general path.
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "ident/smoothing/map_smoother.h"

namespace ident {
namespace {

// A random walk x_{t+1} = x_t + w observed with Laplace-like outliers: quadratic process penalties and an l1
// measurement penalty, n = 1 (a problem of the fast path's structure).
MapSmootherProblem RandomWalkWithOutliers(int T) {
  std::mt19937 rng(7);
  std::normal_distribution<double> normal(0, 1);
  MapSmootherProblem p;
  p.F = {Eigen::MatrixXd::Identity(1, 1)};
  p.H = {Eigen::MatrixXd::Identity(1, 1)};
  p.z.resize(1, T + 1);
  double x = 0;
  for (int t = 0; t <= T; ++t) {
    x += 0.3 * normal(rng);
    p.z(0, t) = x + (t % 7 == 3 ? 5.0 : 0.1) * normal(rng);
  }
  p.process = {models::Penalty::Quadratic(Eigen::MatrixXd::Constant(1, 1, 10.0)),
               models::Penalty::Quadratic(Eigen::MatrixXd::Constant(1, 1, 0.09))};
  p.measurement = {models::Penalty::L1()};
  return p;
}

TEST(MapSmootherIterations, OneCallPerIterationEndingWithTheResultsKktResidual) {
  const MapSmootherProblem p = RandomWalkWithOutliers(200);
  for (const bool fast_path : {true, false}) {
    std::vector<int> iterations;
    std::vector<double> residuals;
    MapSmootherOptions options;
    options.fast_path = fast_path;
    options.on_iteration = [&](int iteration, double kkt) {
      iterations.push_back(iteration);
      residuals.push_back(kkt);
    };
    const MapSmootherResult r = SolveMapSmoother(p, options);
    ASSERT_EQ(r.status, MapSmootherStatus::kConverged) << r.message;
    ASSERT_EQ(iterations.size(), static_cast<std::size_t>(r.iterations) + 1) << fast_path;
    for (std::size_t i = 0; i < iterations.size(); ++i) EXPECT_EQ(iterations[i], static_cast<int>(i));
    EXPECT_EQ(residuals.back(), r.kkt_residual);
    EXPECT_LE(residuals.back(), options.tolerance);
    for (std::size_t i = 0; i + 1 < residuals.size(); ++i) EXPECT_GT(residuals[i], options.tolerance) << i;
    // The residual falls by many decades from the first iteration: the scale `ident smooth` reports progress on.
    EXPECT_GT(residuals.front(), 1e3 * residuals.back());
  }
}

}  // namespace
}  // namespace ident
