// The MAP smoother on long records whose states are far larger than their residuals (a double integrator,
// positions ~ T^1.5): the stopping rule reaches an answer, and the reported duality gap with its error bound
// is a true bound on primal - optimum.
//  - Gaussian: the optimum in closed form, by an independent block Cholesky solve of the normal equations
//    in long double (64-bit mantissa); primal - optimum <= gap + gap_error_bound and dual <= optimum.
//  - l1, Huber, Vapnik, quantile: weak duality, dual <= P(x') for every x', checked at the other models'
//    MAP states; and for an iterate stopped early, whose gap is large, the same lower bound.
#include <array>
#include <cmath>
#include <random>
#include <string>
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
  std::vector<Block> Lc(N);           // Cholesky factor's diagonal blocks, lower triangular [[l11, 0], [l21, l22]]
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
