// Properties of the MAP smoother that need no reference solution:
//  - a problem with a known feasible point x* is never reported infeasible: the solver converges, and its
//    optimum is no worse than x* (primal objective ≤ (P) at x*), for measurement penalties whose domains
//    are wide (piecewise-linear penalties on [−1000, 1000]) or narrow, on both solver paths;
#include <cmath>
#include <random>
#include <string>

#include <gtest/gtest.h>
#include <Eigen/Core>

#include "ident/smoothing/map_smoother.h"
#include "models/penalties.h"

namespace ident {
namespace {

using models::Penalty;

// A convex piecewise-linear penalty on [lo, hi] with a kink at c: slopes −a and b.
Penalty Vee(double lo, double c, double hi, double a, double b) {
  return Penalty::PiecewiseLinear(Eigen::Vector3d(lo, c, hi), Eigen::Vector3d(a * (c - lo), 0, b * (hi - c)));
}

TEST(FeasibleProblem, IsNeverReportedInfeasible) {
  std::mt19937 rng(20261127);
  std::uniform_real_distribution<double> U(0, 1);
  int cases = 0;
  for (int trial = 0; trial < 60; ++trial) {
    const int n = 1 + trial % 3, T = 20 + static_cast<int>(30 * U(rng));
    const double width = std::pow(10.0, -1 + 4 * U(rng));  // domain half-widths 0.1 … 1000
    MapSmootherProblem p;
    Eigen::MatrixXd F = 0.8 * Eigen::MatrixXd::Identity(n, n);
    for (int i = 0; i + 1 < n; ++i) F(i, i + 1) = 0.3;
    p.F = {F};
    p.H = {Eigen::MatrixXd::Ones(1, n)};
    p.process = {Penalty::Huber(1.0, n), trial % 2 ? Penalty::Huber(0.5, n) : Penalty::L1(n)};
    // x*: a state sequence of the model; z = H x* + r with r strictly inside the measurement's domain.
    Eigen::MatrixXd x(n, T + 1);
    x.col(0) = Eigen::VectorXd::Random(n);
    for (int t = 1; t <= T; ++t) x.col(t) = F * x.col(t - 1) + 0.3 * Eigen::VectorXd::Random(n);
    const double lo = -width * (0.2 + U(rng)), hi = width * (0.2 + U(rng)), c = lo + (hi - lo) * U(rng);
    p.measurement = {Vee(lo, c, hi, 0.5 + U(rng), 0.5 + U(rng))};
    p.z.resize(1, T + 1);
    for (int t = 0; t <= T; ++t) p.z(0, t) = x.col(t).sum() + lo + (hi - lo) * (0.02 + 0.96 * U(rng));
    const double at_known_point = PrimalObjective(p, x);
    ASSERT_TRUE(std::isfinite(at_known_point));
    for (const bool fast : {true, false}) {
      MapSmootherOptions o;
      o.fast_path = fast;
      const MapSmootherResult r = SolveMapSmoother(p, o);
      EXPECT_EQ(r.status, MapSmootherStatus::kConverged) << "fast path " << fast << ", trial " << trial << " n " << n
                                                         << " domain [" << lo << ", " << hi << "]: " << r.message;
      EXPECT_LE(r.primal, at_known_point + 1e-8 * (1 + std::abs(at_known_point))) << "trial " << trial;
      EXPECT_LE(std::abs(r.relative_gap), 1e-6) << "trial " << trial;
      ++cases;
    }
  }
  EXPECT_EQ(cases, 120);
}

// The case that was reported infeasible: |r| on [−1000, 1000], a random walk, measurements within ±1.
TEST(FeasibleProblem, WideDomainPiecewiseLinearConverges) {
  MapSmootherProblem p;
  p.F = {Eigen::MatrixXd::Ones(1, 1)};
  p.H = {Eigen::MatrixXd::Ones(1, 1)};
  p.process = {Penalty::Quadratic(Eigen::MatrixXd::Ones(1, 1)), Penalty::Quadratic(0.1 * Eigen::MatrixXd::Ones(1, 1))};
  p.measurement = {Vee(-1000, 0, 1000, 1, 1)};
  p.z.resize(1, 50);
  for (int t = 0; t < 50; ++t) p.z(0, t) = std::sin(0.2 * t);
  const MapSmootherResult r = SolveMapSmoother(p);
  ASSERT_EQ(r.status, MapSmootherStatus::kConverged) << r.message;
  EXPECT_LE(r.gap, 1e-8);
  // The same problem with the domain [−1e6, 1e6] (the indicator inactive in both): the same MAP states.
  p.measurement = {Vee(-1e6, 0, 1e6, 1, 1)};
  const MapSmootherResult wide = SolveMapSmoother(p);
  ASSERT_EQ(wide.status, MapSmootherStatus::kConverged) << wide.message;
  EXPECT_LE((wide.x - r.x).cwiseAbs().maxCoeff(), 1e-6);
}

}  // namespace
}  // namespace ident
