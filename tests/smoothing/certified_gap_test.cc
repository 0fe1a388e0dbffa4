// The MAP smoother on long records whose states are far larger than their residuals (a double integrator,
// positions ~ T^1.5): the stopping rule reaches an answer, and the reported duality gap with its error bound
// is a true bound on primal - optimum.
//  - Gaussian: the optimum in closed form, by an independent block Cholesky solve of the normal equations
//    in long double (64-bit mantissa); primal - optimum <= gap + gap_error_bound and dual <= optimum.
//  - l1, Huber, Vapnik, quantile: problems whose optimum is known by construction (KnownOptimumProblem), the
//    same two inequalities.
//  - l1, Huber, Vapnik, quantile: weak duality, dual <= P(x') for every x', checked at the other models'
//    MAP states; and for an iterate stopped early, whose gap is large, the same lower bound.
#include <algorithm>
#include <array>
#include <cmath>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Core>

#include "ident/smoothing/map_smoother.h"
#include "models/penalties.h"
#include "tests/smoothing/double_integrator.h"

namespace ident {
namespace {

using duality_test::DoubleIntegrator;
using models::Penalty;

// The Gaussian model's optimum: min 1/2|x_0|^2 + sum 1/2|x_t - F x_{t-1}|^2 + sum 1/2 (z_t - x_{t,1})^2 from the
// normal equations A x = b (block tridiagonal, 2 x 2 blocks), by block Cholesky in long double; the objective
// at that x in long double.
long double GaussianOptimum(const MapSmootherProblem& p) {
  using L = long double;
  const int N = p.T() + 1;
  // D_t = I + F'F (t < T) + e1 e1', sub-diagonal block E_t = -F (rows x_t, columns x_{t-1}).
  struct Block {
    L a, b, c;  // symmetric [[a, b], [b, c]]
  };
  std::vector<Block> Lc(N);            // Cholesky factor's diagonal blocks, lower triangular [[l11, 0], [l21, l22]]
  std::vector<std::array<L, 4>> G(N);  // sub-diagonal blocks G_t = E_t Lc_{t-1}^-T, row-major
  std::vector<std::array<L, 2>> y(N), x(N);
  for (int t = 0; t < N; ++t) {
    L a = 1 + 1, b = 0, c = 1;  // I + e1 e1'
    if (t < N - 1) {            // F'F = [[1, 1], [1, 2]]
      a += 1;
      b += 1;
      c += 2;
    }
    L r0 = p.z(0, t), r1 = 0;
    if (t > 0) {
      // E_t = -F = [[-1, -1], [0, -1]]; G_t = E_t Lc_{t-1}^-T: solve G Lc' = E row by row.
      const Block& P = Lc[t - 1];  // a = l11, b = l21, c = l22
      const L E[4] = {-1, -1, 0, -1};
      for (int i = 0; i < 2; ++i) {
        const L g0 = E[2 * i] / P.a;
        const L g1 = (E[2 * i + 1] - g0 * P.b) / P.c;
        G[t][2 * i] = g0;
        G[t][2 * i + 1] = g1;
      }
      a -= G[t][0] * G[t][0] + G[t][1] * G[t][1];
      b -= G[t][2] * G[t][0] + G[t][3] * G[t][1];
      c -= G[t][2] * G[t][2] + G[t][3] * G[t][3];
      r0 -= G[t][0] * y[t - 1][0] + G[t][1] * y[t - 1][1];
      r1 -= G[t][2] * y[t - 1][0] + G[t][3] * y[t - 1][1];
    }
    const L l11 = std::sqrt(a), l21 = b / l11, l22 = std::sqrt(c - l21 * l21);
    Lc[t] = {l11, l21, l22};
    y[t][0] = r0 / l11;
    y[t][1] = (r1 - l21 * y[t][0]) / l22;
  }
  for (int t = N - 1; t >= 0; --t) {  // Lc' x_t = y_t - G_{t+1}' x_{t+1}
    L r0 = y[t][0], r1 = y[t][1];
    if (t < N - 1) {
      r0 -= G[t + 1][0] * x[t + 1][0] + G[t + 1][2] * x[t + 1][1];
      r1 -= G[t + 1][1] * x[t + 1][0] + G[t + 1][3] * x[t + 1][1];
    }
    x[t][1] = r1 / Lc[t].c;
    x[t][0] = (r0 - Lc[t].b * x[t][1]) / Lc[t].a;
  }
  L objective = 0;
  for (int t = 0; t < N; ++t) {
    L w0 = x[t][0], w1 = x[t][1];
    if (t > 0) {
      w0 -= x[t - 1][0] + x[t - 1][1];
      w1 -= x[t - 1][1];
    }
    const L r = p.z(0, t) - x[t][0];
    objective += 0.5L * (w0 * w0 + w1 * w1 + r * r);
  }
  return objective;
}

// The measurement penalties of the known-optimum problems: l1, Huber(1), Vapnik(0.5), Quantile(0.3).
enum class Kink { kL1, kHuber, kVapnik, kQuantile };
constexpr double kEpsilon = 0.5, kTau = 0.3;

// A double-integrator problem (F = [[1, 1], [0, 1]], unit process and prior terms, H = [1, 0]) whose optimum is
// known by construction. With w_t = x_t - F x_{t-1} (w_0 = x_0) the process terms' gradient is w_t - F'w_{t+1}
// (w_{T+1} = 0), so x is optimal if w_t - F'w_{t+1} = H'u_t with u_t in dg(z_t - x_t1); in components
// u_t = w_t1 - w_{t+1,1} and w_t2 = w_{t+1,1} + w_{t+1,2}. The u_t are chosen backwards in time by a bounded
// feedback that keeps w of order one (positions ~ T^1.5), half of them at an end of dom g* (a kink of l1,
// Vapnik or the quantile penalty, the linear part of Huber) and half inside, and z_t = x_t1 + r_t with r_t in
// dg*(u_t). The optimum is the objective at x in long double (at the rounded x: an upper bound on the
// optimum, equal to it up to the rounding of x and z).
struct KnownOptimum {
  MapSmootherProblem problem;
  long double optimum;
};

KnownOptimum KnownOptimumProblem(int T, Kink g, unsigned seed) {
  using L = long double;
  std::mt19937 rng(seed);
  std::bernoulli_distribution kink(0.5), inside_knee(0.3);
  std::uniform_real_distribution<double> noise(-0.5, 0.5), unit(-0.9, 0.9);
  std::exponential_distribution<double> excess(1.0);
  const double u_lo = g == Kink::kQuantile ? kTau - 1 : -1, u_hi = g == Kink::kQuantile ? kTau : 1;
  const int N = T + 1;
  std::vector<double> u(N), r(N);
  std::vector<std::array<double, 2>> w(N);
  double a_next = 0, c_next = 0;  // w_{t+1}
  for (int t = N - 1; t >= 0; --t) {
    const double c = c_next + a_next;                            // w_t2
    const double want = -(0.3 * c + 0.8 * a_next) + noise(rng);  // drives w back towards 0
    if (kink(rng)) {  // an end of dom g*: r beyond the kink, on the side of u's sign
      u[t] = want >= 0 ? u_hi : u_lo;
      const double beyond = excess(rng);
      r[t] = g == Kink::kQuantile ? (u[t] > 0 ? beyond : -beyond)
                                  : u[t] * ((g == Kink::kVapnik  ? kEpsilon
                                             : g == Kink::kHuber ? 1.0
                                                                 : 0.0) +
                                            beyond);
    } else if (g == Kink::kVapnik && inside_knee(rng)) {  // u = 0: r strictly inside the insensitive zone
      u[t] = 0;
      r[t] = kEpsilon * unit(rng);
    } else {
      u[t] = std::clamp(want, u_lo + 0.01, u_hi - 0.01);
      r[t] = g == Kink::kHuber ? u[t] : g == Kink::kVapnik ? (u[t] > 0 ? kEpsilon : u[t] < 0 ? -kEpsilon : 0.0) : 0.0;
    }
    const double a = a_next + u[t];  // w_t1
    w[t] = {a, c};
    a_next = a;
    c_next = c;
  }
  KnownOptimum k;
  MapSmootherProblem& p = k.problem;
  p.F = {(Eigen::MatrixXd(2, 2) << 1, 1, 0, 1).finished()};
  p.H = {(Eigen::MatrixXd(1, 2) << 1, 0).finished()};
  p.process = {Penalty::Quadratic(Eigen::MatrixXd::Identity(2, 2))};
  p.measurement = {g == Kink::kL1       ? Penalty::L1()
                   : g == Kink::kHuber  ? Penalty::Huber(1.0)
                   : g == Kink::kVapnik ? Penalty::Vapnik(kEpsilon)
                                        : Penalty::Quantile(kTau)};
  p.z.resize(1, N);
  std::vector<std::array<double, 2>> x(N);
  L x0 = w[0][0], x1 = w[0][1];
  for (int t = 0; t < N; ++t) {
    if (t > 0) {
      x0 += x1 + w[t][0];
      x1 += w[t][1];
    }
    x[t] = {static_cast<double>(x0), static_cast<double>(x1)};
    p.z(0, t) = x[t][0] + r[t];
  }
  k.optimum = 0;
  for (int t = 0; t < N; ++t) {
    L w0 = x[t][0], w1 = x[t][1];
    if (t > 0) {
      w0 -= static_cast<L>(x[t - 1][0]) + x[t - 1][1];
      w1 -= x[t - 1][1];
    }
    const L res = static_cast<L>(p.z(0, t)) - x[t][0], ar = std::abs(res);
    L measurement = ar;  // l1
    if (g == Kink::kHuber) measurement = ar <= 1 ? 0.5L * res * res : ar - 0.5L;
    if (g == Kink::kVapnik) measurement = std::max(L(0), ar - L(kEpsilon));
    if (g == Kink::kQuantile) measurement = res >= 0 ? L(kTau) * res : L(kTau - 1) * res;
    k.optimum += 0.5L * (w0 * w0 + w1 * w1) + measurement;
  }
  return k;
}

TEST(CertifiedGap, ProblemsWithAKnownOptimumAreCertified) {
  const std::pair<Kink, const char*> models[] = {
      {Kink::kL1, "l1"}, {Kink::kHuber, "Huber"}, {Kink::kVapnik, "Vapnik"}, {Kink::kQuantile, "quantile"}};
  for (const auto& [g, model] : models)
    for (const unsigned seed : {1u, 2u}) {
      const KnownOptimum k = KnownOptimumProblem(20000, g, seed);
      ASSERT_GT(k.problem.z.cwiseAbs().maxCoeff(), 1e4);  // states far above the residuals
      const MapSmootherResult r = SolveMapSmoother(k.problem);
      const std::string name = std::string(model) + ", seed " + std::to_string(seed);
      ASSERT_EQ(r.status, MapSmootherStatus::kConverged) << name << ": " << r.message;
      const double optimum = static_cast<double>(k.optimum);
      const double slack = 1e-14 * std::abs(optimum);  // the rounding of P(x) (a sum of T terms) and of the cast
      EXPECT_LE(r.relative_gap_bound, 1e-8) << name;
      EXPECT_LE(r.primal - optimum, r.gap + r.gap_error_bound + slack) << name << ": primal " << r.primal;
      EXPECT_LE(r.primal - r.gap - r.gap_error_bound, optimum + slack) << name << ": dual " << r.dual;
      EXPECT_LE(std::abs(r.primal - optimum), 1e-8 * optimum) << name;
    }
}

TEST(CertifiedGap, GaussianDoubleIntegratorOfFiftyThousandStepsMatchesTheClosedForm) {
  const MapSmootherProblem p = DoubleIntegrator(50000, Penalty::Quadratic(Eigen::MatrixXd::Identity(1, 1)));
  ASSERT_GT(p.z.cwiseAbs().maxCoeff(), 1e6);  // states far above the residuals
  const MapSmootherResult r = SolveMapSmoother(p);
  ASSERT_EQ(r.status, MapSmootherStatus::kConverged) << r.message;
  const double optimum = static_cast<double>(GaussianOptimum(p));
  const double slack = 1e-14 * std::abs(optimum);  // the rounding of P(x) (a sum of T terms) and of the cast
  EXPECT_LE(r.relative_gap_bound, 1e-8) << r.message;
  EXPECT_GE(r.gap_error_bound, 0.0);
  EXPECT_LE(r.primal - optimum, r.gap + r.gap_error_bound + slack) << "primal " << r.primal << " optimum " << optimum;
  EXPECT_LE(r.primal - r.gap - r.gap_error_bound, optimum + slack) << "dual " << r.dual << " optimum " << optimum;
  EXPECT_LE(std::abs(r.primal - optimum), 1e-9 * optimum);
}

// The dual polish runs when the iterate's own certificate misses the solver's tolerance or the gap a converged
// result must certify. Here a loose tolerance (1e-4) with a tight gap_tolerance (1e-9): the Gaussian model converges
// in one Newton step, whose own dual point certifies only about 4e-8 at this size; polished, it certifies 1e-13.
TEST(CertifiedGap, ALooseToleranceStillPolishesTheDualToTheGapTolerance) {
  const MapSmootherProblem p = DoubleIntegrator(20000, Penalty::Quadratic(Eigen::MatrixXd::Identity(1, 1)));
  MapSmootherOptions options;
  options.tolerance = 1e-4;
  options.gap_tolerance = 1e-9;
  const MapSmootherResult r = SolveMapSmoother(p, options);
  ASSERT_EQ(r.status, MapSmootherStatus::kConverged) << r.message;
  EXPECT_LE(r.relative_gap_bound, 1e-9);
  const double optimum = static_cast<double>(GaussianOptimum(p));
  EXPECT_LE(r.primal - optimum, r.gap + r.gap_error_bound + 1e-14 * std::abs(optimum));
}

TEST(CertifiedGap, PiecewiseLinearAndHuberModelsAreCertifiedByWeakDuality) {
  const int T = 20000;
  const std::vector<Penalty> models = {Penalty::L1(), Penalty::Huber(1.0), Penalty::Vapnik(0.5),
                                       Penalty::Quantile(0.3)};
  std::vector<MapSmootherResult> results;
  std::vector<MapSmootherProblem> problems;
  for (const Penalty& g : models) {
    problems.push_back(DoubleIntegrator(T, g));
    results.push_back(SolveMapSmoother(problems.back()));
    const MapSmootherResult& r = results.back();
    ASSERT_EQ(r.status, MapSmootherStatus::kConverged) << g.Name() << ": " << r.message;
    EXPECT_LE(r.relative_gap_bound, 1e-8) << g.Name() << ": " << r.message;
    EXPECT_GE(r.gap, -r.gap_error_bound) << g.Name();  // a sum of Fenchel-Young gaps, each >= 0
  }
  // dual - error bound <= P(x') for every x': here the MAP states of the other models.
  for (size_t i = 0; i < models.size(); ++i)
    for (size_t j = 0; j < models.size(); ++j) {
      const double other = PrimalObjective(problems[i], results[j].x);
      EXPECT_LE(results[i].primal - results[i].gap - results[i].gap_error_bound, other)
          << models[i].Name() << " at the states of " << models[j].Name();
    }
}

TEST(CertifiedGap, AnIterateStoppedEarlyReportsAGapThatStillBoundsTheOptimum) {
  const MapSmootherProblem p = DoubleIntegrator(5000, Penalty::L1(), 11);
  const MapSmootherResult converged = SolveMapSmoother(p);
  ASSERT_EQ(converged.status, MapSmootherStatus::kConverged) << converged.message;
  for (const bool fast_path : {true, false}) {
    MapSmootherOptions o;
    o.max_iterations = 4;
    o.fast_path = fast_path;
    const MapSmootherResult early = SolveMapSmoother(p, o);
    ASSERT_EQ(early.status, MapSmootherStatus::kMaxIterations) << early.message;
    EXPECT_NE(early.message.find("did not converge in 4 iterations"), std::string::npos) << early.message;
    EXPECT_EQ(early.message.find("infeasible"), std::string::npos) << early.message;
    EXPECT_GT(early.relative_gap, 1e-6);  // far from the optimum: the bound has work to do
    // primal - optimum <= gap + bound, with the converged objective as an upper bound on the optimum.
    EXPECT_LE(early.primal - early.gap - early.gap_error_bound, converged.primal);
    EXPECT_GE(early.primal + 1e-9 * converged.primal, converged.primal - converged.gap - converged.gap_error_bound);
  }
}

}  // namespace
}  // namespace ident
