// The weighting cubic, its bracket and the root selection of spec §4–§5, checked against the maximin
// objective itself (dense grid over both branches + golden-section refinement) [spec §10.1–§10.6, §10.9].
#include "approx/weighting_polynomial.h"
#include "tests/approx/cubic_test_util.h"

#include <cmath>
#include <random>

#include <gtest/gtest.h>

namespace ident::approx {
namespace {

using testing::AbsTerms;
using testing::EvalP;

// Random admissible problems: ν ∈ (1.01, 50)·ν_hard, ξ ≤ ξ_z ≤ 1 over many decades.
std::vector<WeightingProblem> RandomProblems(unsigned seed, int count, bool extreme = true) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  const double ks[] = {1, 1, 2, 3, 4.5, 10};
  std::vector<WeightingProblem> out;
  for (int i = 0; i < count; ++i) {
    WeightingProblem p;
    p.rho = 1 + static_cast<int>(u(rng) * 6);
    p.k = ks[static_cast<int>(u(rng) * 6)];
    p.delta = u(rng) < 0.7 ? 1 : 0;
    p.nu = NuHard(p.rho, p.k, p.delta) * (1.01 + std::pow(u(rng), 2) * 50);
    p.xi_z = 1 - std::pow(10.0, -3 + u(rng) * (extreme ? 7 : 4));
    p.xi = p.xi_z - std::pow(10.0, -3 + u(rng) * (extreme ? 10 : 5));
    out.push_back(p);
  }
  return out;
}

// argmax of LogHFull over (0, 1): log-spaced grid of 4000 points over [1e−14, 1−1e−9] covering both
// branches, then golden-section refinement between the neighbours of the best grid point.
double ArgmaxByGrid(const WeightingProblem& p) {
  const int n = 4000;
  auto at = [&](int i) { return i == n ? 1 - 1e-9 : std::pow(10.0, -14 + 14.0 * i / n) * (1 - 1e-9); };
  int best = 0;
  double best_value = -INFINITY;
  for (int i = 0; i <= n; ++i) {
    const double v = LogHFull(p, at(i));
    if (v > best_value) best_value = v, best = i;
  }
  double a = at(std::max(best - 1, 0)), b = at(std::min(best + 1, n));
  const double g = (std::sqrt(5.0) - 1) / 2;
  double x1 = b - g * (b - a), x2 = a + g * (b - a), f1 = LogHFull(p, x1), f2 = LogHFull(p, x2);
  for (int it = 0; it < 200 && b - a > 1e-17 * b; ++it) {
    if (f1 < f2)
      a = x1, x1 = x2, f1 = f2, x2 = a + g * (b - a), f2 = LogHFull(p, x2);
    else
      b = x2, x2 = x1, f2 = f1, x1 = b - g * (b - a), f1 = LogHFull(p, x1);
  }
  return 0.5 * (a + b);
}

TEST(WeightingPolynomial, RootMaximisesTheFullObjectiveOnADenseGridOverBothBranches) {
  int checked = 0;
  double worst = 0;
  for (const WeightingProblem& p : RandomProblems(7, 300, /*extreme=*/false)) {
    const WeightSolution s = SolveWeight(p);
    ASSERT_TRUE(s.ok);
    const double grid = ArgmaxByGrid(p);
    // The root's objective is not beaten by the grid optimum (up to rounding of log H).
    EXPECT_GE(LogHFull(p, s.beta), LogHFull(p, grid) - 1e-13 * (1 + std::abs(LogHFull(p, grid))));
    const double rel = std::abs(s.beta - grid) / s.beta;
    worst = std::max(worst, rel);
    EXPECT_LT(rel, 1e-7) << "nu=" << p.nu << " rho=" << p.rho << " k=" << p.k << " delta=" << p.delta << " xi=" << p.xi
                         << " xi_z=" << p.xi_z << " beta=" << s.beta << " grid=" << grid;
    ++checked;
  }
  EXPECT_EQ(checked, 300);
  RecordProperty("worst_relative_difference", std::to_string(worst));
}

TEST(WeightingPolynomial, RootLiesInTheBracketWithTinyResidual) {
  for (const WeightingProblem& p : RandomProblems(11, 20000)) {
    const WeightSolution s = SolveWeight(p);
    ASSERT_TRUE(s.ok);
    EXPECT_GE(s.beta, s.beta0);
    EXPECT_LE(s.beta, s.beta_hi);
    if (s.beta != s.beta_hi) {
      std::array<double, 4> mu = WeightingCoefficients(p);
      EXPECT_LE(std::abs(EvalP(mu, s.beta)), 1e-12 * AbsTerms(mu, s.beta))
          << "nu=" << p.nu << " xi=" << p.xi << " xi_z=" << p.xi_z;
    }
  }
}

TEST(WeightingPolynomial, BracketEndsHaveOppositeSignsOnRandomProblems) {  // spec §10.9
  int count = 0;
  for (const WeightingProblem& p : RandomProblems(13, 100000)) {
    const std::array<double, 4> mu = WeightingCoefficients(p);
    const double b0 = Beta0(p), bhi = BetaHi(p);
    ASSERT_GT(EvalP(mu, b0), 0) << "nu=" << p.nu << " xi=" << p.xi << " xi_z=" << p.xi_z;
    ASSERT_LT(EvalP(mu, bhi), 0) << "nu=" << p.nu << " xi=" << p.xi << " xi_z=" << p.xi_z;
    ASSERT_LE(b0, 1 / p.nu * (1 + 1e-15));
    ASSERT_LE(1 / p.nu, bhi);
    ++count;
  }
  EXPECT_EQ(count, 100000);
}

TEST(WeightingPolynomial, ZeroDataVectorGivesTheUpperEndExactly) {  // spec §10.3
  WeightingProblem p{.nu = 5, .xi = 1, .xi_z = 1, .rho = 2, .k = 1, .delta = 1};
  EXPECT_EQ(SolveWeight(p).beta, 0.5);
  for (double k : {1.0, 3.0, 7.5})
    for (int delta : {0, 1}) {
      p = {.nu = 9, .xi = 1, .xi_z = 1, .rho = 3, .k = k, .delta = delta};
      EXPECT_EQ(SolveWeight(p).beta, (k + 1) / (k * 9 + delta - 2));
    }
  // Nearly zero h: the root approaches the upper end continuously.
  p = {.nu = 9, .xi = 1 - 1e-12, .xi_z = 1 - 5e-13, .rho = 3, .k = 1, .delta = 1};
  EXPECT_NEAR(SolveWeight(p).beta, 2.0 / 8, 1e-10);
}

TEST(WeightingPolynomial, SelectsTheGlobalMaximumWhenTwoLocalMaximaExist) {  // spec §5 examples
  WeightingProblem p{.nu = 12, .xi = -3e4, .xi_z = -400, .rho = 2, .k = 1, .delta = 1};
  WeightSolution s = SolveWeight(p);
  EXPECT_EQ(s.num_maxima, 2);
  EXPECT_NEAR(s.beta, 7.5437032e-6, 1e-13);
  EXPECT_NEAR(LogH0(p, s.beta), -12.902, 5e-4);
  EXPECT_NEAR(LogH0(p, 0.051932), -28.256, 5e-3);  // the other (rejected) local maximum
  p = {.nu = 7, .xi = -7.5e5, .xi_z = -8e3, .rho = 5, .k = 1, .delta = 1};
  s = SolveWeight(p);
  EXPECT_EQ(s.num_maxima, 2);
  EXPECT_NEAR(s.beta, 0.16646152, 1e-8);
  EXPECT_NEAR(LogH0(p, s.beta), -12.655, 5e-4);
}

TEST(WeightingPolynomial, LargeDofGivesTheGaussianWeight) {  // spec §7a, §10.4
  for (const WeightingProblem& q : RandomProblems(17, 200)) {
    WeightingProblem p = q;
    p.k = 1e9;
    p.nu = std::max(p.nu, static_cast<double>(p.rho + 2));
    const double nb = p.nu * SolveWeight(p).beta;
    EXPECT_LT(std::abs(nb - 1), 1e-6) << "nu=" << p.nu << " xi=" << p.xi << " xi_z=" << p.xi_z;
  }
}

TEST(WeightingPolynomial, LargeNuGivesTheEmWeightOfTheTModel) {  // spec §7a, §10.5
  // νβ → (k+1)/(k + ê²/D_y) with relative error O(1/ν): below 1e−5 at ν = 1e6 for moderate ê²/D_y,
  // and ten times smaller at ν = 1e7 (within a factor 2) for ê²/D_y up to 1e3.
  std::mt19937_64 rng(19);
  std::uniform_real_distribution<double> u(0, 1);
  for (int i = 0; i < 200; ++i) {
    const double k = 0.5 + 9 * u(rng), e2 = std::pow(10.0, -3 + 6 * u(rng));  // ê²/D_y
    const double xi_z = 1 - 5 * u(rng);
    const double expected = (k + 1) / (k + e2);
    auto err = [&](double nu) {
      const WeightingProblem p{.nu = nu, .xi = xi_z - e2, .xi_z = xi_z, .rho = 1 + i % 5, .k = k, .delta = i % 2};
      return std::abs(nu * SolveWeight(p).beta / expected - 1);
    };
    if (e2 < 30) {
      EXPECT_LT(err(1e6), 1e-5) << "k=" << k << " e2=" << e2;
    }
    EXPECT_LT(err(1e6), 5e-5) << "k=" << k << " e2=" << e2;
    EXPECT_LT(err(1e7), std::max(err(1e6) / 5, 1e-10)) << "k=" << k << " e2=" << e2;
  }
}

TEST(WeightingPolynomial, GrossOutlierWeightDecaysLikeOneOverXi) {  // spec §7a, §10.6
  for (double k : {1.0, 3.0})
    for (int delta : {0, 1})
      for (int rho : {1, 2, 4}) {
        const double nu = rho + k + delta + 2.5;  // > ν_robust
        WeightingProblem p{.nu = nu, .xi = -1e12, .xi_z = 0.3, .rho = rho, .k = k, .delta = delta};
        const double limit = (k + 1) / (nu - delta - rho + 1 - k);
        EXPECT_NEAR(SolveWeight(p).beta * 1e12 / limit, 1, 1e-5) << "k=" << k << " rho=" << rho;
      }
}

TEST(WeightingPolynomial, AtOrBelowNuRobustAGrossOutlierKeepsAnOrderOneOverNuWeight) {  // spec §5
  // ρ = 4, k = δ = 1, ν = 4.5 ≤ ν_robust = 5: νβ tends to a positive constant (≈ 0.75 at ξ_z = 0 by the
  // grid argmax; the spec's "0.8" depends on ξ_z), however large the outlier.
  for (double xi : {-1e6, -1e10, -1e14}) {
    const WeightingProblem p{.nu = 4.5, .xi = xi, .xi_z = 0, .rho = 4, .k = 1, .delta = 1};
    const double beta = SolveWeight(p).beta;
    EXPECT_GT(p.nu * beta, 0.7);
    EXPECT_NEAR(beta / ArgmaxByGrid(p), 1, 1e-6);  // the golden search on log H loses digits at |ξ| = 1e14
  }
}

TEST(WeightingPolynomial, ObjectiveIsContinuousAtTheBranchPoint) {  // spec §3: H is C¹ at β0
  for (const WeightingProblem& p : RandomProblems(23, 200)) {
    const double b0 = Beta0(p);
    EXPECT_NEAR(LogHFull(p, b0 * (1 - 1e-12)), LogH0(p, b0), 1e-9 * (1 + std::abs(LogH0(p, b0))));
  }
}

TEST(WeightingPolynomial, NuHardMatchesTheSpecTable) {  // spec §2.1 table
  EXPECT_EQ(NuHard(2, 1, 1), 3);
  EXPECT_EQ(NuHard(5, 1, 1), 5);
  EXPECT_EQ(NuHard(2, 1, 0), 4);
  EXPECT_EQ(NuHard(7, 1, 0), 6);
  EXPECT_EQ(NuRobust(4, 1, 1), 5);
}

TEST(WeightingPolynomial, HandlesExtremeScalingAfterOutliersOnATinyScale) {  // spec §5, §10.12
  for (double xi : {-1e14, -3e17, -1e20}) {
    const WeightingProblem p{.nu = 7, .xi = xi, .xi_z = -2.5, .rho = 4, .k = 1, .delta = 1};
    const WeightSolution s = SolveWeight(p);
    EXPECT_GE(s.beta, s.beta0);
    EXPECT_LE(s.beta, s.beta_hi);
    EXPECT_NEAR(s.beta * std::abs(xi) / (2.0 / (7 - 1 - 4 + 1 - 1)), 1, 1e-4) << xi;
  }
}

// ê·dβ/dê = 2u·dβ/du at fixed ξ_z (u = ξ_z − ξ): against central differences of the solved β, and for large
// ν against the EM weight's limit: ν·(β + ê·dβ/dê) → ψ' = (k+1)(k−u)/(k+u)², the Student-t score's slope.
TEST(WeightingPolynomial, ElasticityMatchesCentralDifferencesAndTheScoreSlope) {
  for (const double k : {1.0, 3.0, 10.0})
    for (const double u : {0.05, 0.7, 3.0, 30.0})
      for (const double xi_z : {0.4, -0.5, -3.0}) {
        const double nu = 60;
        auto beta_at = [&](double uu) { return SolveWeight({nu, xi_z - uu, xi_z, 4, k, 1}).beta; };
        const double h = 1e-6 * u, numeric = 2 * u * (beta_at(u + h) - beta_at(u - h)) / (2 * h);
        const double analytic = WeightElasticity({nu, xi_z - u, xi_z, 4, k, 1}, beta_at(u));
        EXPECT_NEAR(analytic, numeric, 1e-6 * std::abs(numeric) + 1e-12) << k << " " << u << " " << xi_z;
      }
  for (const double k : {1.0, 3.0})
    for (const double u : {0.1, 1.0, 4.0}) {
      const double nu = 1e6, beta = SolveWeight({nu, -2 - u, -2, 3, k, 1}).beta;
      const double slope = nu * (beta + WeightElasticity({nu, -2 - u, -2, 3, k, 1}, beta));
      EXPECT_NEAR(slope, (k + 1) * (k - u) / ((k + u) * (k + u)), 1e-3) << k << " " << u;
    }
}

}  // namespace
}  // namespace ident::approx
