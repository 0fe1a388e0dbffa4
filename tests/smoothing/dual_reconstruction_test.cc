// Uniqueness of the reconstruction of the states from the dual solution (ident/smoothing/map_smoother.h):
// w_t in d f_t*(y_t) determines w_t only where f_t* is differentiable at y_t. Checked on an instance
// solved by hand (l1 process noise: total-variation smoothing of a step, with dual states that sit on
// the boundary of dom f* both degenerately and strictly), and on l1 / Huber / quadratic / Vapnik
// process noise, where the flagged steps are compared with the steps at which the primal solution
// lies on a linear piece of f_t (then d f_t*(y_t) is a segment or a ray) or f_t* has a kink at y_t,
// verified by finite differences of the conjugate.
#include <algorithm>
#include <cmath>
#include <random>
#include <set>

#include <gtest/gtest.h>

#include "ident/smoothing/map_smoother.h"

namespace ident {
namespace {

using models::Penalty;

// Scalar random walk observed directly: x_{t+1} = x_t + w_{t+1}, z_t = x_t + v_t; a step of height 5
// at t = 3 and small noise elsewhere.
MapSmootherProblem StepProblem(const Penalty& process, const std::vector<double>& z) {
  MapSmootherProblem p;
  p.F = {Eigen::MatrixXd::Identity(1, 1)};
  p.H = {Eigen::MatrixXd::Identity(1, 1)};
  p.z = Eigen::Map<const Eigen::MatrixXd>(z.data(), 1, static_cast<Eigen::Index>(z.size()));
  p.process = {process};
  p.measurement = {Penalty::Quadratic(Eigen::MatrixXd::Identity(1, 1))};
  return p;
}

std::set<int> Flagged(const MapSmootherResult& r) { return {r.nonunique_steps.begin(), r.nonunique_steps.end()}; }

// Does f* have a kink (or the end of its domain) within h of y? Second differences of the conjugate:
// f* smooth with curvature <= c gives |f*(y+h) - 2 f*(y) + f*(y-h)| <= c h^2; a kink of jump J in the
// slope at distance d < h gives J (h - d). 1e-12 (1 + |f*(y)|) allows for rounding.
bool ConjugateKinkWithin(const Penalty& f, const Eigen::VectorXd& y, double h, double curvature) {
  for (int i = 0; i < y.size(); ++i) {
    Eigen::VectorXd a = y, b = y;
    a(i) += h;
    b(i) -= h;
    const double fa = f.Conjugate(a), fb = f.Conjugate(b), fy = f.Conjugate(y);
    if (!std::isfinite(fa) || !std::isfinite(fb)) return true;
    if (std::abs(fa - 2 * fy + fb) > 2 * curvature * h * h + 1e-12 * (1 + std::abs(fy))) return true;
  }
  return false;
}

TEST(DualReconstruction, TotalVariationStepSolvedByHand) {
  // min |x_0| + sum_t |x_t - x_{t-1}| + 1/2 sum_t (z_t - x_t)^2 with z = (0, 0, 0, 5, 5, 5). By hand:
  // x = (0, 0, 0, 14/3, 14/3, 14/3), u = z - x = (0, 0, 0, 1/3, 1/3, 1/3), y_t = sum_{s >= t} u_s =
  // (1, 1, 1, 1, 2/3, 1/3) (KKT: y_t in d|w_t|, y_3 = 1 = sign(w_3), |y_t| <= 1 where w_t = 0), value 29/6.
  // Steps 0..2 are degenerate (y_t on the bound with w_t = 0): an interior point reaches them only to
  // O(sqrt(mu)), here about 2e-5, which is the tolerance on x and y below.
  // d f*(y) for f* = indicator of [-1, 1] is the normal cone: [0, inf) at y = 1 (t = 0..3: t = 0..2 with
  // w_t = 0 are degenerate, t = 3 strict), {0} inside (t = 4, 5). The dual alone gives w = 0, x = 0.
  const MapSmootherProblem p = StepProblem(Penalty::L1(), {0, 0, 0, 5, 5, 5});
  const MapSmootherResult r = SolveMapSmoother(p);
  ASSERT_EQ(r.status, MapSmootherStatus::kConverged) << r.message;
  const double h = 14.0 / 3.0;
  const std::vector<double> x = {0, 0, 0, h, h, h}, y = {1, 1, 1, 1, 2.0 / 3, 1.0 / 3};
  for (int t = 0; t < 6; ++t) {
    EXPECT_NEAR(r.x(0, t), x[t], 1e-4) << t;
    EXPECT_NEAR(r.y(0, t), y[t], 1e-4) << t;
  }
  EXPECT_NEAR(r.primal, 29.0 / 6.0, 1e-9);
  EXPECT_EQ(Flagged(r), (std::set<int>{0, 1, 2, 3}));
  EXPECT_FALSE(r.reconstruction_unique);
  EXPECT_NEAR(r.max_abs_x_difference, h, 1e-4);  // x_from_dual = 0
}

TEST(DualReconstruction, QuadraticProcessNoiseIsAlwaysUnique) {
  const MapSmootherProblem p =
      StepProblem(Penalty::Quadratic(Eigen::MatrixXd::Constant(1, 1, 0.3)), {0.1, -0.2, 0.05, 5, 5.2, 4.9, 5.1});
  const MapSmootherResult r = SolveMapSmoother(p);
  ASSERT_EQ(r.status, MapSmootherStatus::kConverged) << r.message;
  EXPECT_TRUE(r.nonunique_steps.empty());
  EXPECT_TRUE(r.reconstruction_unique);
  EXPECT_LT(r.max_abs_x_difference, 1e-9);
}

TEST(DualReconstruction, HuberProcessNoiseIsNotUniqueExactlyWhereTheJumpExceedsKappa) {
  // Huber(kappa): f* = y^2/2 on [-kappa, kappa]; d f*(y) = {y} inside, a ray at |y| = kappa, which is
  // where |w_t| >= kappa. The small wiggles stay inside, the step of 5 does not.
  const double kappa = 1.0;
  const MapSmootherProblem p = StepProblem(Penalty::Huber(kappa), {0.1, -0.2, 0.05, 5, 5.2, 4.9, 5.1});
  const MapSmootherResult r = SolveMapSmoother(p);
  ASSERT_EQ(r.status, MapSmootherStatus::kConverged) << r.message;
  EXPECT_EQ(Flagged(r), (std::set<int>{3}));
  EXPECT_GT(std::abs(r.w(0, 3)), kappa + 0.5);
  EXPECT_NEAR(std::abs(r.y(0, 3)), kappa, 1e-8);
  for (int t = 0; t <= p.T(); ++t) {
    const bool kink = ConjugateKinkWithin(p.ft(t), r.y.col(t), 1e-5, 1.0);
    EXPECT_EQ(kink, t == 3) << t;
  }
  // Before the first non-unique step the rebuilt states equal x; from it on they do not.
  for (int t = 0; t < 3; ++t) EXPECT_NEAR(r.x_from_dual(0, t), r.x(0, t), 1e-9) << t;
  EXPECT_GT(std::abs(r.x_from_dual(0, 3) - r.x(0, 3)), 1.0);
}

TEST(DualReconstruction, VapnikProcessNoiseIsUniqueOnlyWhereTheResidualSitsOnTheKnee) {
  // Vapnik(eps): f* = eps |y| on [-1, 1]: d f*(0) = [-eps, eps] (every |w_t| < eps), rays at |y| = 1
  // (|w_t| > eps); only |w_t| = eps with 0 < |y_t| < 1 determines w_t.
  const double eps = 0.5;
  const MapSmootherProblem p = StepProblem(Penalty::Vapnik(eps), {0.1, -0.2, 0.05, 5, 5.2, 4.9, 5.1, 3.0});
  const MapSmootherResult r = SolveMapSmoother(p);
  ASSERT_EQ(r.status, MapSmootherStatus::kConverged) << r.message;
  const std::set<int> flagged = Flagged(r);
  int checked = 0;
  for (int t = 0; t <= p.T(); ++t) {
    const double w = std::abs(r.w(0, t)), y = std::abs(r.y(0, t));
    if (w < eps - 1e-6 || w > eps + 1e-6) {  // on a linear piece of f: d f*(y_t) is a segment or a ray
      EXPECT_TRUE(flagged.count(t)) << t << " w " << r.w(0, t) << " y " << r.y(0, t);
      EXPECT_TRUE(ConjugateKinkWithin(p.ft(t), r.y.col(t), 1e-4, 0.0)) << t;
      ++checked;
    } else if (y > 1e-3 && y < 1 - 1e-3) {  // on the knee, y strictly inside: unique
      EXPECT_FALSE(flagged.count(t)) << t;
      EXPECT_FALSE(ConjugateKinkWithin(p.ft(t), r.y.col(t), 1e-4, 0.0)) << t;
      ++checked;
    }
  }
  EXPECT_GE(checked, 6);
  EXPECT_FALSE(r.reconstruction_unique);
}

TEST(DualReconstruction, FlaggedStepsAreKinksAndUnflaggedStepsRebuildThePrimalOnRandomInstances) {
  // l1, Huber, quadratic and Vapnik process noise (n = 2) with l1 / Huber measurement noise. At a flagged
  // step either f_t* has a kink near y_t (finite differences) or w_t and the rebuilt increment are two
  // different elements of d f_t*(y_t) (both satisfy Fenchel-Young with equality). Unflagged steps have
  // f_t* smooth around y_t and their increment equal to w_t, so x_from_dual = x up to the first flagged step.
  std::mt19937 rng(17);
  std::normal_distribution<double> N(0, 1);
  std::bernoulli_distribution jump(0.15);
  int flagged_total = 0, unflagged_total = 0;
  for (int trial = 0; trial < 8; ++trial) {
    const int T = 30;
    MapSmootherProblem p;
    p.F = {(Eigen::MatrixXd(2, 2) << 1, 0.1, 0, 0.9).finished()};
    p.H = {(Eigen::MatrixXd(1, 2) << 1, 0.5).finished()};
    p.z.resize(1, T + 1);
    Eigen::Vector2d x(0, 0);
    for (int t = 0; t <= T; ++t) {
      x = p.F[0] * x + 0.2 * Eigen::Vector2d(N(rng), N(rng)) +
          (jump(rng) ? Eigen::Vector2d(3 * N(rng), 0) : Eigen::Vector2d(0, 0));
      p.z(0, t) = x(0) + 0.5 * x(1) + 0.3 * N(rng);
    }
    const Penalty processes[] = {Penalty::L1(2), Penalty::Huber(0.4, 2),
                                 Penalty::Quadratic(0.05 * Eigen::MatrixXd::Identity(2, 2)), Penalty::Vapnik(0.1, 2)};
    p.process = {Penalty::Quadratic(Eigen::MatrixXd::Identity(2, 2)), processes[trial % 4]};
    p.measurement = {trial % 2 ? Penalty::Huber(1.0) : Penalty::L1()};
    const MapSmootherResult r = SolveMapSmoother(p);
    ASSERT_EQ(r.status, MapSmootherStatus::kConverged) << "trial " << trial << ": " << r.message;
    const std::set<int> flagged = Flagged(r);
    if (trial % 4 == 2) {
      EXPECT_TRUE(flagged.empty()) << "quadratic process noise, trial " << trial;
    } else {
      EXPECT_FALSE(flagged.empty()) << "trial " << trial;
    }
    const int first = flagged.empty() ? T + 1 : *flagged.begin();
    for (int t = 0; t < first; ++t)
      EXPECT_LT((r.x_from_dual.col(t) - r.x.col(t)).cwiseAbs().maxCoeff(), 1e-6) << "trial " << trial << " t " << t;
    for (int t = 0; t <= T; ++t) {
      const Penalty& f = p.ft(t);
      const Eigen::VectorXd y = r.y.col(t), w = r.w.col(t), g = f.ConjugateGradient(y);
      const double curvature = f.kind() == Penalty::Kind::kQuadratic ? f.matrix().maxCoeff() : 1.0;
      // Fenchel-Young: w_t is in d f_t*(y_t) at the optimum.
      EXPECT_NEAR(f.Value(w) + f.Conjugate(y), w.dot(y), 1e-6 * (1 + w.cwiseAbs().sum())) << trial << " " << t;
      if (flagged.count(t)) {
        ++flagged_total;
        EXPECT_TRUE(ConjugateKinkWithin(f, y, 1e-3, curvature) || (w - g).cwiseAbs().maxCoeff() > 1e-6)
            << "trial " << trial << " t " << t;
      } else {
        ++unflagged_total;
        EXPECT_FALSE(ConjugateKinkWithin(f, y, 1e-7, curvature)) << "trial " << trial << " t " << t;
        EXPECT_LT((w - g).cwiseAbs().maxCoeff(), 1e-6 * (1 + w.cwiseAbs().maxCoeff())) << trial << " " << t;
      }
    }
  }
  EXPECT_GT(flagged_total, 20);
  EXPECT_GT(unflagged_total, 20);
}

}  // namespace
}  // namespace ident
