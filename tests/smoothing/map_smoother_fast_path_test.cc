// The MAP smoother's fused fast path (ident/smoothing/internal/map_smoother_fast_path.h) against the general
// interior-point path (MapSmootherOptions::fast_path = false: per-term PLQ dispatch, block Cholesky) on random problems
// of the fast path's structure, n = 1..4, time-invariant and time-varying; which problems take it. The agreement of
// both paths with an independent dense method is in map_smoother_test.cc
// (L1AndHuberMatchAnExhaustiveActiveSetSolutionOfTheDenseDual runs both). The fast path's factorisation from both
// ends, on one thread or two, is checked against itself and the general path on the shortest records.
#include "ident/smoothing/internal/map_smoother_fast_path.h"

#include <cmath>
#include <random>
#include <string>

#include <gtest/gtest.h>

#include "ident/smoothing/map_smoother.h"
#include "tests/smoothing/double_integrator.h"
#include "tests/smoothing/random_matrices.h"

namespace ident {
namespace {

using duality_test::RandomMatrix;
using duality_test::RandomSpd;
using models::Penalty;

// A measurement penalty of the fast path's kind: l1, Huber, quantile or a scalar box monitoring function.
Penalty FastPathPenalty(std::mt19937& rng, int kind) {
  std::uniform_real_distribution<double> U(0, 1);
  switch (kind % 4) {
    case 0:
      return Penalty::L1();
    case 1:
      return Penalty::Huber(0.2 + 2 * U(rng));
    case 2:
      return Penalty::Quantile(0.1 + 0.8 * U(rng));
    default:
      return Penalty::BoxMonitoring(Eigen::VectorXd::Constant(1, -0.5 - U(rng)),
                                    Eigen::VectorXd::Constant(1, 0.5 + U(rng)),
                                    Eigen::MatrixXd::Constant(1, 1, U(rng)));
  }
}

// A random stable-ish system with heavy-tailed measurements; time-varying F, H and penalties if `varying`.
MapSmootherProblem RandomProblem(std::mt19937& rng, int n, int T, bool varying, int kind) {
  MapSmootherProblem p;
  const int num_F = varying ? T : 1, num_H = varying ? T + 1 : 1;
  for (int t = 0; t < num_F; ++t) p.F.push_back(0.9 * Eigen::MatrixXd::Identity(n, n) + RandomMatrix(rng, n, n, 0.1));
  for (int t = 0; t < num_H; ++t) p.H.push_back(RandomMatrix(rng, 1, n));
  p.z = RandomMatrix(rng, 1, T + 1, 2.0);
  std::bernoulli_distribution outlier(0.1);
  for (int t = 0; t <= T; ++t)
    if (outlier(rng)) p.z(0, t) += 10 * RandomMatrix(rng, 1, 1)(0, 0);
  if (varying) {
    p.process.push_back(Penalty::Quadratic(RandomSpd(rng, n, 1.0)));
    for (int t = 1; t <= T; ++t) p.process.push_back(Penalty::Quadratic(RandomSpd(rng, n, 0.05 + 0.1 * (t % 3))));
    for (int t = 0; t <= T; ++t) p.measurement.push_back(FastPathPenalty(rng, kind + t));
  } else {
    p.process = {Penalty::Quadratic(RandomSpd(rng, n, 1.0)), Penalty::Quadratic(RandomSpd(rng, n, 0.1))};
    p.measurement = {FastPathPenalty(rng, kind)};
  }
  return p;
}

TEST(MapSmootherFastPath, AppliesExactlyToBoundFreeProcessAndScalarBoxMeasurementTerms) {
  std::mt19937 rng(5);
  for (int kind = 0; kind < 4; ++kind)
    for (int n = 1; n <= 4; ++n) {
      MapSmootherProblem p = RandomProblem(rng, n, 6, kind % 2 == 1, kind);
      EXPECT_TRUE(internal::MapSmootherFastPathApplies(p)) << "n = " << n << ", kind " << kind;
    }
  const MapSmootherProblem base = RandomProblem(rng, 2, 6, false, 0);
  MapSmootherProblem p = base;
  p.measurement = {Penalty::Vapnik(0.5)};  // B is 2 x 1
  EXPECT_FALSE(internal::MapSmootherFastPathApplies(p));
  p.measurement = {Penalty::PiecewiseLinear(Eigen::Vector3d(-1, 0, 2), Eigen::Vector3d(1, 0, 1))};
  EXPECT_FALSE(internal::MapSmootherFastPathApplies(p));
  p.measurement = {Penalty::Quadratic(Eigen::MatrixXd::Identity(1, 1))};  // no bounds: no multipliers
  EXPECT_FALSE(internal::MapSmootherFastPathApplies(p));
  p = base;
  p.process = {Penalty::Quadratic(Eigen::MatrixXd::Identity(2, 2)), Penalty::Huber(1.0, 2)};  // bounded f_t
  EXPECT_FALSE(internal::MapSmootherFastPathApplies(p));
  p = base;  // nz = 2
  p.H = {RandomMatrix(rng, 2, 2)};
  p.z = RandomMatrix(rng, 2, 7);
  p.measurement = {Penalty::L1(2)};
  EXPECT_FALSE(internal::MapSmootherFastPathApplies(p));
  p = RandomProblem(rng, 5, 6, false, 0);  // n = 5: the general path's run-time size
  EXPECT_FALSE(internal::MapSmootherFastPathApplies(p));
}

// Both paths run the same iteration (same start, directions equal in exact arithmetic, same stopping rule),
// so the solutions agree to the interior point's accuracy and the iteration counts nearly coincide.
TEST(MapSmootherFastPath, AgreesWithTheGeneralPathOnRandomProblems) {
  std::mt19937 rng(2025);
  MapSmootherOptions general;
  general.fast_path = false;
  int trials = 0;
  for (int n = 1; n <= 4; ++n)
    for (int kind = 0; kind < 4; ++kind)
      for (bool varying : {false, true}) {
        const int T = 10 + 13 * kind + 7 * n;
        const MapSmootherProblem p = RandomProblem(rng, n, T, varying, kind);
        ASSERT_TRUE(internal::MapSmootherFastPathApplies(p));
        const MapSmootherResult fast = SolveMapSmoother(p), slow = SolveMapSmoother(p, general);
        const std::string label = "n = " + std::to_string(n) + ", kind " + std::to_string(kind) +
                                  (varying ? ", time-varying" : ", time-invariant");
        ASSERT_EQ(fast.status, MapSmootherStatus::kConverged) << label << ": " << fast.message;
        ASSERT_EQ(slow.status, MapSmootherStatus::kConverged) << label << ": " << slow.message;
        const double x_scale = 1 + slow.x.cwiseAbs().maxCoeff();
        EXPECT_LT((fast.x - slow.x).cwiseAbs().maxCoeff(), 1e-7 * x_scale) << label;
        EXPECT_LT((fast.u - slow.u).cwiseAbs().maxCoeff(), 1e-6) << label;
        EXPECT_NEAR(fast.primal, slow.primal, 1e-9 * (1 + std::abs(slow.primal))) << label;
        EXPECT_LE(std::abs(fast.relative_gap), 1e-8) << label;
        EXPECT_LE(fast.dual_infeasibility, 1e-9) << label;
        EXPECT_LE(std::abs(fast.iterations - slow.iterations), 2) << label;
        // Quadratic process noise: the dual determines the states (w = Q y).
        EXPECT_TRUE(fast.reconstruction_unique) << label;
        // x_from_dual accumulates the error of y through up to 70 steps of the dynamics, so how close it comes
        // to x depends on the instance's conditioning and on rounding: for n = 3, kind 3, time-invariant it
        // is 7.9e-6 in a gcc build and 5.5e-3 in a clang ASan build — on both paths alike. The property here
        // is that the fast path rebuilds the states as well as the general path does.
        EXPECT_LT(fast.max_abs_x_difference, 1e-5 * x_scale + 2 * slow.max_abs_x_difference)
            << label << ", general path " << slow.max_abs_x_difference;
        // (P) at the fast path's x is not improved by moving any coordinate.
        for (int t = 0; t <= T; t += 3)
          for (int i = 0; i < n; ++i)
            for (double h : {-1e-4, 1e-4}) {
              Eigen::MatrixXd x = fast.x;
              x(i, t) += h;
              EXPECT_GE(PrimalObjective(p, x), fast.primal - 1e-9 * (1 + std::abs(fast.primal))) << label;
            }
        ++trials;
      }
  EXPECT_EQ(trials, 32);
}

// The factorisation runs from both ends and meets at m = T/2, on one thread or two: the same operations in the
// same order either way, so the results are bit-identical; the shortest records (m = 0, an empty top or bottom
// half) agree with the general path.
// Every field of two results, bit for bit.
void ExpectSameResult(const MapSmootherResult& a, const MapSmootherResult& b, const std::string& label) {
  EXPECT_EQ(a.status, b.status) << label;
  EXPECT_EQ(a.message, b.message) << label;
  EXPECT_EQ(a.iterations, b.iterations) << label;
  EXPECT_EQ(a.kkt_residual, b.kkt_residual) << label;
  EXPECT_TRUE(a.x == b.x) << label;
  EXPECT_TRUE(a.w == b.w) << label;
  EXPECT_TRUE(a.u == b.u) << label;
  EXPECT_TRUE(a.y == b.y) << label;
  EXPECT_EQ(a.primal, b.primal) << label;
  EXPECT_EQ(a.dual, b.dual) << label;
  EXPECT_EQ(a.gap, b.gap) << label;
  EXPECT_EQ(a.gap_error_bound, b.gap_error_bound) << label;
  EXPECT_EQ(a.relative_gap_bound, b.relative_gap_bound) << label;
  EXPECT_EQ(a.dual_infeasibility, b.dual_infeasibility) << label;
  EXPECT_TRUE(a.x_from_dual == b.x_from_dual) << label;
  EXPECT_EQ(a.max_abs_x_difference, b.max_abs_x_difference) << label;
  EXPECT_EQ(a.nonunique_steps, b.nonunique_steps) << label;
}

TEST(MapSmootherFastPath, GivesTheSameResultOnOneThreadOrTwo) {
  std::mt19937 rng(77);
  MapSmootherOptions one, two, general;
  one.threads = 1;
  two.threads = 2;
  general.fast_path = false;
  for (int n = 1; n <= 4; ++n)
    for (int T : {0, 1, 2, 3, 8, 41})
      for (bool varying : {false, true}) {
        const MapSmootherProblem p = RandomProblem(rng, n, T, varying, n + T);
        const std::string label = "n = " + std::to_string(n) + ", T = " + std::to_string(T) +
                                  (varying ? ", time-varying" : ", time-invariant");
        const MapSmootherResult a = SolveMapSmoother(p, one), b = SolveMapSmoother(p, two);
        ASSERT_EQ(a.status, MapSmootherStatus::kConverged) << label << ": " << a.message;
        ExpectSameResult(a, b, label);
        if (T <= 3) {
          const MapSmootherResult slow = SolveMapSmoother(p, general);
          ASSERT_EQ(slow.status, MapSmootherStatus::kConverged) << label << ": " << slow.message;
          EXPECT_LT((a.x - slow.x).cwiseAbs().maxCoeff(), 1e-7 * (1 + slow.x.cwiseAbs().maxCoeff())) << label;
          EXPECT_NEAR(a.primal, slow.primal, 1e-9 * (1 + std::abs(slow.primal))) << label;
        }
      }
  // A loose tolerance: the iterate's own dual point misses gap_tolerance, so the finish polishes it and certifies
  // again (its second certificate and reconstruction run after the two-task ones).
  for (int T : {300, 3000}) {
    const MapSmootherProblem p = duality_test::DoubleIntegrator(T, Penalty::L1());
    for (MapSmootherOptions* o : {&one, &two}) o->tolerance = 1e-4, o->gap_tolerance = 1e-9;
    ExpectSameResult(SolveMapSmoother(p, one), SolveMapSmoother(p, two), "polished, T = " + std::to_string(T));
  }
  MapSmootherOptions negative;
  negative.threads = -1;
  EXPECT_NE(negative.Validate().find("threads = -1"), std::string::npos) << negative.Validate();
}

// A longer benchmark-like problem (the model of bench/map_smoother_benchmark.cc at T = 3000).
TEST(MapSmootherFastPath, AgreesWithTheGeneralPathOnALongSequence) {
  std::mt19937 rng(42);
  std::normal_distribution<double> normal(0, 1);
  std::exponential_distribution<double> expo(2.0);
  std::bernoulli_distribution sign(0.5), outlier(0.05);
  const int T = 3000;
  MapSmootherProblem p;
  p.F = {(Eigen::MatrixXd(2, 2) << 0.99, 0.1, 0, 0.95).finished()};
  p.H = {(Eigen::MatrixXd(1, 2) << 1, 0).finished()};
  p.z.resize(1, T + 1);
  Eigen::Vector2d x(normal(rng), normal(rng));
  for (int t = 0; t <= T; ++t) {
    if (t > 0) x = p.F[0] * x + 0.1 * Eigen::Vector2d(normal(rng), normal(rng));
    p.z(0, t) = x(0) + (sign(rng) ? 1 : -1) * expo(rng) + (outlier(rng) ? 10 * normal(rng) : 0.0);
  }
  MapSmootherOptions general;
  general.fast_path = false;
  for (const Penalty& g : {Penalty::L1(), Penalty::Huber(1.0)}) {
    p.process = {Penalty::Quadratic(Eigen::MatrixXd::Identity(2, 2)),
                 Penalty::Quadratic(0.01 * Eigen::MatrixXd::Identity(2, 2))};
    p.measurement = {g};
    const MapSmootherResult fast = SolveMapSmoother(p), slow = SolveMapSmoother(p, general);
    ASSERT_EQ(fast.status, MapSmootherStatus::kConverged) << g.Name() << ": " << fast.message;
    ASSERT_EQ(slow.status, MapSmootherStatus::kConverged) << g.Name() << ": " << slow.message;
    EXPECT_LT((fast.x - slow.x).cwiseAbs().maxCoeff(), 1e-7 * (1 + slow.x.cwiseAbs().maxCoeff())) << g.Name();
    EXPECT_NEAR(fast.primal, slow.primal, 1e-10 * std::abs(slow.primal)) << g.Name();
    EXPECT_LE(std::abs(fast.relative_gap), 1e-9) << g.Name();
    EXPECT_LE(std::abs(fast.iterations - slow.iterations), 2) << g.Name();
  }
}

}  // namespace
}  // namespace ident
