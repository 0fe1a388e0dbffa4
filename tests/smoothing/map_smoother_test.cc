// MAP smoother and its dual control problem (ident/smoothing/map_smoother.h) checked against independent
// methods: a Kalman filter + Rauch-Tung-Striebel smoother for quadratic penalties, an exhaustive
// active-set solution of the dense dual box QP for l1/Huber measurement noise, weak duality at
// arbitrary feasible points, and the duality gap on random PLQ instances.
#include "ident/smoothing/map_smoother.h"
#include "common/dense_decompositions.h"

#include <cmath>
#include <random>

#include <gtest/gtest.h>
#include <Eigen/Cholesky>
#include <Eigen/LU>

#include "common/error.h"
#include "tests/smoothing/random_matrices.h"

namespace ident {
namespace {

using duality_test::RandomMatrix;
using duality_test::RandomSpd;
using models::Penalty;

// Kalman filter with prior x_0 ~ N(0, P0), then the RTS backward pass: the posterior means E[x_t | z_0..T].
Eigen::MatrixXd RtsSmoother(const std::vector<Eigen::MatrixXd>& F, const std::vector<Eigen::MatrixXd>& H,
                            const Eigen::MatrixXd& z, const Eigen::MatrixXd& P0, const Eigen::MatrixXd& Q,
                            const Eigen::MatrixXd& R) {
  const int T = static_cast<int>(z.cols()) - 1, n = static_cast<int>(P0.rows());
  std::vector<Eigen::VectorXd> xf(T + 1), xp(T + 1);
  std::vector<Eigen::MatrixXd> Pf(T + 1), Pp(T + 1);
  for (int t = 0; t <= T; ++t) {
    if (t == 0) {
      xp[0] = Eigen::VectorXd::Zero(n);
      Pp[0] = P0;
    } else {
      xp[t] = F[t - 1] * xf[t - 1];
      Pp[t] = F[t - 1] * Pf[t - 1] * F[t - 1].transpose() + Q;
    }
    const Eigen::MatrixXd S = H[t] * Pp[t] * H[t].transpose() + R;
    const Eigen::MatrixXd K = Pp[t] * H[t].transpose() * S.inverse();
    xf[t] = xp[t] + K * (z.col(t) - H[t] * xp[t]);
    Pf[t] = (Eigen::MatrixXd::Identity(n, n) - K * H[t]) * Pp[t];
  }
  Eigen::MatrixXd xs(n, T + 1);
  xs.col(T) = xf[T];
  for (int t = T - 1; t >= 0; --t) {
    const Eigen::MatrixXd C = Pf[t] * F[t].transpose() * Pp[t + 1].inverse();
    xs.col(t) = xf[t] + C * (xs.col(t + 1) - xp[t + 1]);
  }
  return xs;
}

TEST(MapSmoother, QuadraticPenaltiesReproduceTheRauchTungStriebelSmoother) {
  std::mt19937 rng(11);
  for (int trial = 0; trial < 5; ++trial) {
    const int n = 2 + trial % 3, nz = 1 + trial % 2, T = 25 + 5 * trial;
    MapSmootherProblem p;
    for (int t = 0; t < T; ++t) p.F.push_back(0.7 * Eigen::MatrixXd::Identity(n, n) + RandomMatrix(rng, n, n, 0.2));
    for (int t = 0; t <= T; ++t) p.H.push_back(RandomMatrix(rng, nz, n));
    p.z = RandomMatrix(rng, nz, T + 1, 2.0);
    const Eigen::MatrixXd P0 = RandomSpd(rng, n), Q = RandomSpd(rng, n), R = RandomSpd(rng, nz);
    p.process = {Penalty::Quadratic(P0), Penalty::Quadratic(Q)};
    p.measurement = {Penalty::Quadratic(R)};
    const MapSmootherResult r = SolveMapSmoother(p);
    ASSERT_EQ(r.status, MapSmootherStatus::kConverged) << r.message;
    const Eigen::MatrixXd rts = RtsSmoother(p.F, p.H, p.z, P0, Q, R);
    EXPECT_LT((r.x - rts).cwiseAbs().maxCoeff(), 1e-9 * (1 + rts.cwiseAbs().maxCoeff())) << "trial " << trial;
    EXPECT_LT(std::abs(r.relative_gap), 1e-10);
    EXPECT_LT(r.max_abs_x_difference, 1e-9 * (1 + rts.cwiseAbs().maxCoeff()));
  }
}

// A random convex piecewise-linear penalty with support [lo, hi] around 0.
Penalty RandomPiecewiseLinear(std::mt19937& rng) {
  std::uniform_real_distribution<double> U(0, 1);
  const int J = 3 + static_cast<int>(U(rng) * 5);
  Eigen::VectorXd knots(J + 1), values(J + 1);
  knots(0) = -3 - U(rng);
  for (int j = 1; j <= J; ++j) knots(j) = knots(j - 1) + 0.3 + 1.5 * U(rng);
  double slope = -2 - U(rng);
  values(0) = 4;
  for (int j = 1; j <= J; ++j) {
    values(j) = values(j - 1) + slope * (knots(j) - knots(j - 1));
    slope += 0.2 + 1.5 * U(rng);
  }
  return Penalty::PiecewiseLinear(knots, values);
}

Penalty RandomScalarPenalty(std::mt19937& rng, int kind) {
  std::uniform_real_distribution<double> U(0, 1);
  switch (kind % 6) {
    case 0:
      return Penalty::L1();
    case 1:
      return Penalty::Huber(0.2 + 2 * U(rng));
    case 2:
      return Penalty::Vapnik(0.1 + U(rng));
    case 3:
      return Penalty::Quantile(0.1 + 0.8 * U(rng));
    case 4:
      return Penalty::BoxMonitoring(Eigen::VectorXd::Constant(1, -0.5 - U(rng)),
                                    Eigen::VectorXd::Constant(1, 0.5 + U(rng)),
                                    Eigen::MatrixXd::Constant(1, 1, U(rng)));
    default:
      return RandomPiecewiseLinear(rng);
  }
}

MapSmootherProblem RandomPlqProblem(std::mt19937& rng, int T, int trial) {
  const int n = 2;
  MapSmootherProblem p;
  for (int t = 0; t < T; ++t) {
    Eigen::MatrixXd F(2, 2);
    F << 1, 0.1 * (1 + t % 3), 0, 0.95;
    p.F.push_back(F + RandomMatrix(rng, n, n, 0.05));
  }
  for (int t = 0; t <= T; ++t) p.H.push_back(RandomMatrix(rng, 1, n));
  p.z = RandomMatrix(rng, 1, T + 1, 1.5);
  std::uniform_real_distribution<double> U(0, 1);
  switch (trial % 3) {
    case 0:
      p.process = {Penalty::Quadratic(RandomSpd(rng, n)), Penalty::Quadratic(RandomSpd(rng, n))};
      break;
    case 1:
      p.process = {Penalty::Quadratic(RandomSpd(rng, n)), Penalty::Huber(0.5 + U(rng), n)};
      break;
    default:
      p.process = {Penalty::L1(n), Penalty::Vapnik(0.05, n)};
      break;
  }
  for (int t = 0; t <= T; ++t) p.measurement.push_back(RandomScalarPenalty(rng, static_cast<int>(U(rng) * 6)));
  return p;
}

TEST(MapSmoother, DualityGapVanishesOnRandomPlqInstances) {
  std::mt19937 rng(2024);
  for (int trial = 0; trial < 30; ++trial) {
    const MapSmootherProblem p = RandomPlqProblem(rng, 20 + trial, trial);
    const MapSmootherResult r = SolveMapSmoother(p);
    ASSERT_EQ(r.status, MapSmootherStatus::kConverged) << "trial " << trial << ": " << r.message;
    EXPECT_TRUE(std::isfinite(r.primal) && std::isfinite(r.dual)) << "trial " << trial;
    EXPECT_LE(std::abs(r.relative_gap), 1e-8) << "trial " << trial << " primal " << r.primal << " dual " << r.dual;
    EXPECT_LE(r.dual_infeasibility, 1e-9) << "trial " << trial;
    // Where the reconstruction w_t in d f_t*(y_t) is unique it rebuilds the primal states.
    if (r.reconstruction_unique) {
      EXPECT_LT(r.max_abs_x_difference, 1e-6 * (1 + r.x.cwiseAbs().maxCoeff())) << "trial " << trial;
    }
    if (trial % 3 == 0) {
      EXPECT_TRUE(r.reconstruction_unique) << "quadratic process noise, trial " << trial;
    }
    // The reported dual point satisfies the control dynamics of (D) up to its projection onto dom f*.
    EXPECT_LE((DualStates(p, r.u) - r.y).cwiseAbs().maxCoeff(),
              r.dual_infeasibility + 1e-12 * (1 + r.y.cwiseAbs().maxCoeff()));
    // No coordinate perturbation of x improves (P).
    for (int t = 0; t <= p.T(); t += 5)
      for (int i = 0; i < 2; ++i)
        for (double h : {-1e-4, 1e-4}) {
          Eigen::MatrixXd x = r.x;
          x(i, t) += h;
          EXPECT_GE(PrimalObjective(p, x, 1e-8), r.primal - 1e-9 * (1 + std::abs(r.primal)));
        }
  }
}

TEST(MapSmoother, WeakDualityHoldsAtArbitraryFeasiblePoints) {
  // dual(u) <= primal(x) for every x and every u in dom g* (y = DualStates(u) is unconstrained for
  // quadratic f): the sign convention of (D) makes it a lower bound.
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> U(-1, 1);
  MapSmootherProblem p = RandomPlqProblem(rng, 12, 0);
  p.measurement = {Penalty::Huber(0.8)};
  const MapSmootherResult opt = SolveMapSmoother(p);
  ASSERT_EQ(opt.status, MapSmootherStatus::kConverged);
  for (int trial = 0; trial < 200; ++trial) {
    Eigen::MatrixXd u(1, p.T() + 1), x = RandomMatrix(rng, 2, p.T() + 1, 2.0);
    for (int t = 0; t <= p.T(); ++t) u(0, t) = 0.8 * U(rng);
    const double dual = DualObjective(p, u), primal = PrimalObjective(p, x);
    EXPECT_LE(dual, primal);
    EXPECT_LE(dual, opt.primal + 1e-9);  // every dual value bounds the optimum from below
    EXPECT_GE(primal, opt.dual - 1e-9);  // every primal value bounds it from above
  }
  // Outside dom g* the dual is -inf.
  Eigen::MatrixXd u = Eigen::MatrixXd::Constant(1, p.T() + 1, 0.9);
  EXPECT_EQ(DualObjective(p, u), -models::kInfinity);
}

// Exhaustive active-set solution of the dense dual box QP
//   max_u z'u - c/2 |u|^2 - 1/2 y' Qbar y,  y = A^-T H' u,  |u_t| <= b
// (l1: c = 0, b = 1; Huber: c = 1, b = kappa), then x = A^-1 Qbar y (w = grad f*(y)). Every pattern
// (u_t = -b, free, +b) is tried; the one meeting the KKT conditions is the unique solution.
struct DenseSolution {
  Eigen::MatrixXd x;
  double dual;
};

DenseSolution SolveDualByEnumeration(const MapSmootherProblem& p, const Eigen::MatrixXd& P0, const Eigen::MatrixXd& Q,
                                     double c, double b) {
  const int T = p.T(), n = p.state_dim(), N = T + 1, nx = n * N;
  Eigen::MatrixXd A = Eigen::MatrixXd::Identity(nx, nx), Hbig = Eigen::MatrixXd::Zero(N, nx),
                  Qbar = Eigen::MatrixXd::Zero(nx, nx);
  for (int t = 0; t < N; ++t) {
    if (t > 0) A.block(t * n, (t - 1) * n, n, n) = -p.Ft(t - 1);
    Hbig.block(t, t * n, 1, n) = p.Ht(t);
    Qbar.block(t * n, t * n, n, n) = t == 0 ? P0 : Q;
  }
  const Eigen::MatrixXd Ainv = A.inverse();
  const Eigen::MatrixXd Y = Ainv.transpose() * Hbig.transpose();  // y = Y u
  const Eigen::MatrixXd K = Y.transpose() * Qbar * Y + c * Eigen::MatrixXd::Identity(N, N);
  const Eigen::VectorXd z = p.z.row(0).transpose();
  int patterns = 1;
  for (int i = 0; i < N; ++i) patterns *= 3;
  for (int code = 0; code < patterns; ++code) {
    Eigen::VectorXi state(N);  // -1, 0 (free), +1
    for (int i = 0, k = code; i < N; ++i, k /= 3) state(i) = k % 3 - 1;
    std::vector<int> free;
    Eigen::VectorXd u = Eigen::VectorXd::Zero(N);
    for (int i = 0; i < N; ++i)
      if (state(i) == 0)
        free.push_back(i);
      else
        u(i) = state(i) * b;
    if (!free.empty()) {
      const int m = static_cast<int>(free.size());
      Eigen::MatrixXd KF(m, m);
      Eigen::VectorXd rhs(m);
      for (int i = 0; i < m; ++i) {
        rhs(i) = z(free[i]) - K.row(free[i]).dot(u);
        for (int j = 0; j < m; ++j) KF(i, j) = K(free[i], free[j]);
      }
      const Eigen::VectorXd uF = dense::Ldlt(KF).solve(rhs);
      for (int i = 0; i < m; ++i) u(free[i]) = uF(i);
    }
    const Eigen::VectorXd grad = z - K * u;  // gradient of the concave objective
    bool kkt = true;
    for (int i = 0; i < N && kkt; ++i) {
      if (state(i) == 0)
        kkt = std::abs(u(i)) <= b;
      else
        kkt = state(i) * grad(i) >= -1e-12;
    }
    if (!kkt) continue;
    const Eigen::VectorXd w = Qbar * (Y * u), xs = Ainv * w;
    DenseSolution s;
    s.x = Eigen::Map<const Eigen::MatrixXd>(xs.data(), n, N);
    s.dual = z.dot(u) - 0.5 * u.dot(K * u);
    return s;
  }
  ADD_FAILURE() << "no KKT pattern found";
  return {};
}

TEST(MapSmoother, L1AndHuberMatchAnExhaustiveActiveSetSolutionOfTheDenseDual) {
  std::mt19937 rng(77);
  for (int trial = 0; trial < 8; ++trial) {
    const int T = 7, n = 2;
    MapSmootherProblem p;
    p.F = {(Eigen::MatrixXd(2, 2) << 1, 1, 0, 1).finished()};
    p.H = {RandomMatrix(rng, 1, n)};
    p.z = RandomMatrix(rng, 1, T + 1, 3.0);
    const Eigen::MatrixXd P0 = RandomSpd(rng, n), Q = RandomSpd(rng, n);
    p.process = {Penalty::Quadratic(P0), Penalty::Quadratic(Q)};
    const bool huber = trial % 2 == 1;
    const double kappa = 0.6;
    p.measurement = {huber ? Penalty::Huber(kappa) : Penalty::L1()};
    const DenseSolution dense = SolveDualByEnumeration(p, P0, Q, huber ? 1.0 : 0.0, huber ? kappa : 1.0);
    EXPECT_NEAR(PrimalObjective(p, dense.x), dense.dual, 1e-9 * (1 + std::abs(dense.dual)));
    for (bool fast_path : {true, false}) {  // the fused fast path (the default here) and the general path
      MapSmootherOptions options;
      options.fast_path = fast_path;
      const MapSmootherResult r = SolveMapSmoother(p, options);
      ASSERT_EQ(r.status, MapSmootherStatus::kConverged) << r.message;
      EXPECT_LT((r.x - dense.x).cwiseAbs().maxCoeff(), 1e-7 * (1 + dense.x.cwiseAbs().maxCoeff()))
          << "trial " << trial << ", fast path " << fast_path;
      EXPECT_NEAR(r.primal, dense.dual, 1e-9 * (1 + std::abs(dense.dual))) << "fast path " << fast_path;
      // With quadratic process noise the dual reconstruction w = Q y is exact.
      EXPECT_TRUE(r.reconstruction_unique);
      EXPECT_LT(r.max_abs_x_difference, 1e-7 * (1 + dense.x.cwiseAbs().maxCoeff()));
    }
  }
}

TEST(MapSmoother, ReportsAnInfeasibleProblem) {
  // |w_t| <= 0.1 and |z_t - x_t| <= 0.1 cannot both hold when z jumps from 0 to 5.
  Eigen::VectorXd knots(2), values(2);
  knots << -0.1, 0.1;
  values << 0, 0;
  MapSmootherProblem p;
  p.F = {Eigen::MatrixXd::Identity(1, 1)};
  p.H = {Eigen::MatrixXd::Identity(1, 1)};
  p.z = (Eigen::MatrixXd(1, 3) << 0, 0, 5).finished();
  p.process = {Penalty::PiecewiseLinear(knots, values)};
  p.measurement = {Penalty::PiecewiseLinear(knots, values)};
  const MapSmootherResult r = SolveMapSmoother(p);
  EXPECT_NE(r.status, MapSmootherStatus::kConverged) << r.message;
  EXPECT_EQ(r.primal, models::kInfinity);
  if (r.status == MapSmootherStatus::kInfeasible) {  // the evidence: where the multipliers diverge
    EXPECT_NE(r.message.find("at t = "), std::string::npos) << r.message;
  }
}

TEST(MapSmoother, RejectsMisSizedProblemsNamingTheField) {
  MapSmootherProblem p;
  p.F = {Eigen::MatrixXd::Identity(2, 2)};
  p.H = {Eigen::MatrixXd::Ones(1, 2)};
  p.z = Eigen::MatrixXd::Zero(1, 5);
  p.process = {Penalty::Quadratic(Eigen::MatrixXd::Identity(2, 2))};
  p.measurement = {Penalty::L1()};
  EXPECT_NO_THROW(SolveMapSmoother(p));
  auto message = [](const MapSmootherProblem& q) {
    try {
      SolveMapSmoother(q);
    } catch (const InvalidArgument& e) {
      return std::string(e.what());
    }
    return std::string("no exception");
  };
  MapSmootherProblem bad = p;
  bad.F = {Eigen::MatrixXd::Identity(3, 3)};
  EXPECT_NE(message(bad).find("F[0] is 3x3"), std::string::npos) << message(bad);
  bad = p;
  bad.H = {Eigen::MatrixXd::Ones(1, 2), Eigen::MatrixXd::Ones(1, 2)};
  EXPECT_NE(message(bad).find("H has 2 matrices"), std::string::npos) << message(bad);
  bad = p;
  bad.measurement = {Penalty::L1(2)};
  EXPECT_NE(message(bad).find("measurement penalty 0 has dimension 2"), std::string::npos) << message(bad);
  bad = p;
  bad.process = {Penalty::L1(1)};
  EXPECT_NE(message(bad).find("process penalty 0"), std::string::npos) << message(bad);
  bad = p;
  bad.z(0, 2) = std::nan("");
  EXPECT_NE(message(bad).find("z has a non-finite"), std::string::npos) << message(bad);
}

TEST(MapSmoother, VectorMeasurementsWithACoupledBoxMonitoringFunctionCloseTheGap) {
  // nz = 2 with rho_{U,M}, U a box and M non-diagonal (the solver's dense K = M + D path), and
  // componentwise l1 / Vapnik on alternate steps; n = 3, time-varying F.
  std::mt19937 rng(31);
  Eigen::MatrixXd M(2, 2);
  M << 1.0, 0.4, 0.4, 0.6;
  const Penalty box =
      Penalty::BoxMonitoring((Eigen::VectorXd(2) << -1, -0.5).finished(), (Eigen::VectorXd(2) << 1, 2).finished(), M);
  for (int trial = 0; trial < 4; ++trial) {
    const int T = 15, n = 3;
    MapSmootherProblem p;
    for (int t = 0; t < T; ++t) p.F.push_back(0.9 * Eigen::MatrixXd::Identity(n, n) + RandomMatrix(rng, n, n, 0.1));
    p.H = {RandomMatrix(rng, 2, n)};
    p.z = RandomMatrix(rng, 2, T + 1, 2.0);
    p.process = {Penalty::Quadratic(RandomSpd(rng, n)), Penalty::Huber(0.7, n)};
    for (int t = 0; t <= T; ++t)
      p.measurement.push_back(t % 3 == 0 ? box : t % 3 == 1 ? Penalty::L1(2) : Penalty::Vapnik(0.3, 2));
    const MapSmootherResult r = SolveMapSmoother(p);
    ASSERT_EQ(r.status, MapSmootherStatus::kConverged) << r.message;
    EXPECT_LE(std::abs(r.relative_gap), 1e-8) << "trial " << trial;
    EXPECT_NEAR(PrimalObjective(p, r.x), r.primal, 1e-9 * (1 + std::abs(r.primal)));
    for (int t = 0; t <= T; t += 3)
      for (int i = 0; i < n; ++i)
        for (double h : {-1e-4, 1e-4}) {
          Eigen::MatrixXd x = r.x;
          x(i, t) += h;
          EXPECT_GE(PrimalObjective(p, x), r.primal - 1e-9 * (1 + std::abs(r.primal)));
        }
  }
}

}  // namespace
}  // namespace ident

namespace ident {
namespace {

// Quadratic (bound-free) penalties interleaved with bounded ones at single time steps: the solver keeps no
// multipliers for the quadratic terms (u = K^-1 (B r - b) implicitly) and rebuilds their dual controls from
// x. Checked against the optimality conditions written out here: u_t = C_t^-1 (z_t - H_t x_t) for the
// quadratic measurement steps (stationarity of g_t), a vanishing duality gap, and no coordinate
// perturbation of x improving (P); bounded process noise (Huber) makes the Newton blocks E_t vary too.
TEST(MapSmoother, QuadraticTermsWithoutMultipliersMixWithBoundedOnes) {
  std::mt19937 rng(77);
  for (int trial = 0; trial < 6; ++trial) {
    const int T = 25 + trial;
    MapSmootherProblem p;
    Eigen::MatrixXd F(2, 2);
    F << 1, 0.1, 0, 0.95;
    p.F = {F + RandomMatrix(rng, 2, 2, 0.05)};
    p.H = {RandomMatrix(rng, 1, 2)};
    p.z = RandomMatrix(rng, 1, T + 1, 1.5);
    p.process = {Penalty::Quadratic(RandomSpd(rng, 2)),
                 trial % 2 ? Penalty::Huber(0.3, 2) : Penalty::Quadratic(RandomSpd(rng, 2))};
    const double c = 0.5 + trial * 0.1;  // covariance of the quadratic measurement steps
    std::vector<bool> quadratic(T + 1);
    for (int t = 0; t <= T; ++t) {
      quadratic[t] = t % 3 != 1;
      p.measurement.push_back(quadratic[t] ? Penalty::Quadratic(Eigen::MatrixXd::Constant(1, 1, c))
                              : t % 2      ? Penalty::L1()
                                           : Penalty::Huber(0.5));
    }
    const MapSmootherResult r = SolveMapSmoother(p);
    ASSERT_EQ(r.status, MapSmootherStatus::kConverged) << r.message;
    EXPECT_LE(std::abs(r.relative_gap), 1e-8) << "trial " << trial;
    for (int t = 0; t <= T; ++t)
      if (quadratic[t]) {
        const double expected = (p.z(0, t) - p.H[0].row(0).dot(r.x.col(t))) / c;
        EXPECT_NEAR(r.u(0, t), expected, 1e-9 * (1 + std::abs(expected))) << "trial " << trial << " t " << t;
      } else {
        EXPECT_LE(std::abs(r.u(0, t)), (t % 2 ? 1.0 : 0.5) + 1e-12);  // dom g*: [-1, 1] (l1), [-0.5, 0.5] (Huber)
      }
    for (int t = 0; t <= T; t += 3)
      for (int i = 0; i < 2; ++i)
        for (double h : {-1e-4, 1e-4}) {
          Eigen::MatrixXd x = r.x;
          x(i, t) += h;
          EXPECT_GE(PrimalObjective(p, x), r.primal - 1e-9 * (1 + std::abs(r.primal))) << "trial " << trial;
        }
  }
}

}  // namespace
}  // namespace ident
