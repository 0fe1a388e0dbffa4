// Differential properties of the MAP smoother that need no reference solution: its answer does not
// depend on the units of the data.
//  - Scaled: with x' = s·x, z' = s·z and every penalty replaced by ρ_s(r) = s²·ρ(r/s) — Quadratic(C)
//    unchanged, Huber(κ) → Huber(sκ), BoxMonitoring(lo, hi, M) → BoxMonitoring(s·lo, s·hi, M),
//    PiecewiseLinear(k, v) → PiecewiseLinear(s·k, s²·v) — the objective of (P) at s·x is s² times the
//    original at x [BCW eq. (2.1)], so the MAP states are s·x̂ and the optimum s²·(P)*.
//  - Shifted: z' = z + d with a piecewise-linear measurement penalty whose knots move by d leaves every
//    residual's penalty, and so the optimum and (where unique) x̂, unchanged.
// Both solver paths, s from 1e-6 to 1e6.
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Core>

#include "ident/smoothing/map_smoother.h"
#include "models/penalties.h"

namespace ident {
namespace {

using models::Penalty;

// ρ_s(r) = s²·ρ(r/s) for the penalties the problems below use.
Penalty ScaledPenalty(const Penalty& f, double s) {
  switch (f.kind()) {
    case Penalty::Kind::kQuadratic:
      return f;
    case Penalty::Kind::kHuber:
      return Penalty::Huber(s * f.parameter(), f.dim());
    case Penalty::Kind::kPiecewiseLinear:
      return Penalty::PiecewiseLinear(s * f.knots(), s * s * f.values());
    case Penalty::Kind::kBoxMonitoring: {
      const models::PlqForm& q = f.plq();
      return Penalty::BoxMonitoring(s * q.lo, s * q.hi, f.matrix());
    }
    default:
      ADD_FAILURE() << "no scaled form for " << f.Name();
      return f;
  }
}

// A convex piecewise-linear penalty on [lo, hi] with a kink at c: slopes −a and b.
Penalty ScalableVee(double lo, double c, double hi, double a, double b) {
  return Penalty::PiecewiseLinear(Eigen::Vector3d(lo, c, hi), Eigen::Vector3d(a * (c - lo), 0, b * (hi - c)));
}

// Random problems mixing every penalty kind that has a scaled form, with measurements from a state
// sequence of the model plus noise inside the measurement penalty's domain.
MapSmootherProblem RandomScalableProblem(int trial, std::mt19937& rng) {
  std::uniform_real_distribution<double> U(0, 1);
  const int n = 1 + trial % 2, T = 15 + static_cast<int>(25 * U(rng));
  MapSmootherProblem p;
  Eigen::MatrixXd F = 0.9 * Eigen::MatrixXd::Identity(n, n);
  if (n == 2) F(0, 1) = 0.2;
  p.F = {F};
  p.H = {Eigen::MatrixXd::Ones(1, n)};
  const Penalty process =
      trial % 3 == 0   ? Penalty::Huber(0.5 + U(rng), n)
      : trial % 3 == 1 ? Penalty::Quadratic(0.3 * Eigen::MatrixXd::Identity(n, n))
                       : Penalty::BoxMonitoring(Eigen::VectorXd::Constant(n, -1), Eigen::VectorXd::Constant(n, 1),
                                                Eigen::MatrixXd::Identity(n, n));
  p.process = {Penalty::Quadratic(Eigen::MatrixXd::Identity(n, n)), process};
  const double lo = -(1 + 2 * U(rng)), hi = 1 + 2 * U(rng);
  switch (trial % 4) {
    case 0:
      p.measurement = {Penalty::Huber(0.3 + U(rng))};
      break;
    case 1:
      p.measurement = {Penalty::Quadratic(Eigen::MatrixXd::Constant(1, 1, 0.5))};
      break;
    case 2:
      p.measurement = {Penalty::BoxMonitoring(Eigen::VectorXd::Constant(1, -1), Eigen::VectorXd::Constant(1, 2),
                                              Eigen::MatrixXd::Constant(1, 1, 0.5))};
      break;
    default:
      p.measurement = {ScalableVee(lo, lo + (hi - lo) * U(rng), hi, 0.5 + U(rng), 0.5 + U(rng))};
      break;
  }
  std::uniform_real_distribution<double> V(-1, 1);
  auto random_vector = [&] { return Eigen::VectorXd(Eigen::VectorXd::NullaryExpr(n, [&] { return V(rng); })); };
  Eigen::MatrixXd x(n, T + 1);
  x.col(0) = random_vector();
  for (int t = 1; t <= T; ++t) x.col(t) = F * x.col(t - 1) + 0.5 * random_vector();
  p.z.resize(1, T + 1);
  for (int t = 0; t <= T; ++t) p.z(0, t) = x.col(t).sum() + lo + (hi - lo) * (0.05 + 0.9 * U(rng));
  return p;
}

// With a quadratic process penalty (on x_0 and every w_t) the objective is strictly convex in x and the MAP
// states are unique; with Huber or box process penalties a piecewise-linear measurement penalty can leave
// directions in which the objective is flat to the solver's tolerance, and only the optimum is compared.
bool StrictlyConvex(int trial) { return trial % 3 == 1; }

MapSmootherProblem ScaledProblem(const MapSmootherProblem& p, double s) {
  MapSmootherProblem q = p;
  q.z *= s;
  for (Penalty& f : q.process) f = ScaledPenalty(f, s);
  for (Penalty& g : q.measurement) g = ScaledPenalty(g, s);
  return q;
}

TEST(ScaledProblem, MapStatesScaleWithTheData) {
  std::mt19937 rng(20261128);
  int cases = 0;
  for (int trial = 0; trial < 24; ++trial) {
    const MapSmootherProblem p = RandomScalableProblem(trial, rng);
    for (const bool fast : {true, false}) {
      MapSmootherOptions o;
      o.fast_path = fast;
      const MapSmootherResult base = SolveMapSmoother(p, o);
      ASSERT_EQ(base.status, MapSmootherStatus::kConverged) << "trial " << trial << ": " << base.message;
      const double x_scale = base.x.cwiseAbs().maxCoeff();
      for (const double s : {1e-6, 1e-3, 1e3, 1e6}) {
        const MapSmootherResult r = SolveMapSmoother(ScaledProblem(p, s), o);
        ASSERT_EQ(r.status, MapSmootherStatus::kConverged)
            << "trial " << trial << " s " << s << " fast " << fast << ": " << r.message;
        if (StrictlyConvex(trial)) {
          EXPECT_LE((r.x / s - base.x).cwiseAbs().maxCoeff(), 1e-6 * x_scale)
              << "trial " << trial << " s " << s << " fast " << fast;
        }
        EXPECT_NEAR(r.primal / (s * s), base.primal, 1e-7 * (1 + std::abs(base.primal)))
            << "trial " << trial << " s " << s << " fast " << fast;
        EXPECT_LE(std::abs(r.relative_gap), 1e-6) << "trial " << trial << " s " << s << " fast " << fast;
        ++cases;
      }
    }
  }
  EXPECT_EQ(cases, 24 * 2 * 4);
}

TEST(ShiftedProblem, MapStatesDoNotMoveWithTheMeasurementOrigin) {
  std::mt19937 rng(20261129);
  int cases = 0;
  for (int trial = 3; trial < 48; trial += 4) {  // the piecewise-linear measurement penalty
    const MapSmootherProblem p = RandomScalableProblem(trial, rng);
    const Eigen::VectorXd knots = p.measurement[0].knots(), values = p.measurement[0].values();
    for (const bool fast : {true, false}) {
      MapSmootherOptions o;
      o.fast_path = fast;
      const MapSmootherResult base = SolveMapSmoother(p, o);
      ASSERT_EQ(base.status, MapSmootherStatus::kConverged) << "trial " << trial << ": " << base.message;
      for (const double d : {-1e4, -3.5, 7.25, 1e4}) {
        MapSmootherProblem q = p;
        q.z.array() += d;
        q.measurement = {Penalty::PiecewiseLinear(knots.array() + d, values)};
        const MapSmootherResult r = SolveMapSmoother(q, o);
        ASSERT_EQ(r.status, MapSmootherStatus::kConverged) << "trial " << trial << " d " << d << ": " << r.message;
        if (StrictlyConvex(trial)) {
          EXPECT_LE((r.x - base.x).cwiseAbs().maxCoeff(), 1e-6 * (1 + base.x.cwiseAbs().maxCoeff()))
              << "trial " << trial << " d " << d << " fast " << fast;
        }
        EXPECT_NEAR(r.primal, base.primal, 1e-7 * (1 + std::abs(base.primal))) << "trial " << trial << " d " << d;
        ++cases;
      }
    }
  }
  EXPECT_EQ(cases, 12 * 2 * 4);
}

}  // namespace
}  // namespace ident
