// The fast weight solver SolveWeight (the estimators' hot path) against the spec §5 algorithm as printed,
// SolveWeightReference, on 10⁵+ seeded random weighting problems over the whole admissible range —
// ν from 1.0001·ν_hard to 1e7, k from 0.2 to 1e6, ρ up to 40, δ ∈ {0, 1}, ξ_z from 1 − 1e−16 down to
// −1e8, ê²/D_y = ξ_z − ξ from 0 to 1e20 (gross outliers) — plus h = 0, ê = 0 and z = 0 exactly; and
// the fast root's own residual and bracket; and a long-double root of the same cubic as an independent
// oracle. The dense-grid maximin checks of weighting_polynomial_test.cc also run on SolveWeight.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "approx/weighting_polynomial.h"
#include "tests/approx/cubic_test_util.h"

namespace ident::approx {
namespace {

using testing::AbsTerms;
using testing::EvalP;

std::string Describe(const WeightingProblem& p) {
  char buf[256];
  std::snprintf(buf, sizeof buf, "nu=%.17g xi=%.17g xi_z=%.17g rho=%d k=%.17g delta=%d", p.nu, p.xi, p.xi_z, p.rho, p.k,
                p.delta);
  return buf;
}

// Random admissible problems over the extremes of every parameter (log-uniform where the range spans decades).
std::vector<WeightingProblem> ExtremeProblems(unsigned seed, int count) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  auto log_uniform = [&](double lo, double hi) { return std::pow(10.0, lo + (hi - lo) * u(rng)); };
  std::vector<WeightingProblem> out;
  out.reserve(count);
  for (int i = 0; i < count; ++i) {
    WeightingProblem p;
    const double r = u(rng);
    p.rho = r < 0.5 ? 1 + static_cast<int>(u(rng) * 6) : 1 + static_cast<int>(u(rng) * 40);
    const double kr = u(rng);
    p.k = kr < 0.4 ? 1 : kr < 0.6 ? 3 : log_uniform(std::log10(0.2), 6);
    p.delta = u(rng) < 0.7 ? 1 : 0;
    const double hard = NuHard(p.rho, p.k, p.delta);
    const double nr = u(rng);
    p.nu = nr < 0.2   ? hard * (1 + log_uniform(-4, -1))  // near admissibility
           : nr < 0.9 ? hard * (1 + log_uniform(-1, 2))
                      : hard * log_uniform(2, 7);  // large ν (long memory)
    const double zr = u(rng);
    p.xi_z = zr < 0.1 ? 1 : zr < 0.8 ? 1 - log_uniform(-16, 1) : 1 - log_uniform(1, 8);  // novel regressors
    const double er = u(rng);
    p.xi = er < 0.05 ? p.xi_z : p.xi_z - (er < 0.85 ? log_uniform(-16, 4) : log_uniform(4, 20));  // outliers
    out.push_back(p);
  }
  return out;
}

// The root's condition number: relative change of β per relative rounding of the terms of P,
// cond = Σ|μ_i β^i| / (β·|P'(β)|). The reference itself is only accurate to ~ε·cond.
double Condition(const WeightingProblem& p, double beta) {
  const std::array<double, 4> mu = WeightingCoefficients(p);
  const double dp = (3 * mu[3] * beta + 2 * mu[2]) * beta + mu[1];
  return AbsTerms(mu, beta) / (beta * std::abs(dp));
}

// An independent oracle: the root of the same (double-coefficient) cubic next to `beta`, by bisection with
// P evaluated in long double (64-bit mantissa: 2000× less rounding than double).
long double LongDoubleRoot(const WeightingProblem& p, double beta) {
  const std::array<double, 4> mu = WeightingCoefficients(p);
  auto P = [&](long double b) { return ((static_cast<long double>(mu[3]) * b + mu[2]) * b + mu[1]) * b + mu[0]; };
  long double lo = beta, hi = beta, w = beta * 1e-15L;
  for (int i = 0; i < 200 && !(P(lo) > 0); ++i) lo -= w, w *= 2;  // P decreases through a maximum's root
  w = beta * 1e-15L;
  for (int i = 0; i < 200 && !(P(hi) < 0); ++i) hi += w, w *= 2;
  for (int i = 0; i < 200; ++i) {
    const long double m = (lo + hi) / 2;
    if (m == lo || m == hi) break;
    (P(m) > 0 ? lo : hi) = m;
  }
  return (lo + hi) / 2;
}

constexpr double kEps = 2.220446049250313e-16;

TEST(WeightSolver, AgreesWithTheSpecAlgorithmOnExtremeRandomProblems) {
  const std::vector<WeightingProblem> problems = ExtremeProblems(20261123, 120000);
  double worst_well = 0, worst_ill = 0, worst_oracle = 0;
  int two_maxima = 0, ill_conditioned = 0, fast_iterations = 0, reference_iterations = 0, rising_first = 0;
  for (const WeightingProblem& p : problems) {
    const WeightSolution fast = SolveWeight(p), ref = SolveWeightReference(p);
    {  // P rises, then falls on the bracket: one crossing, which the inline common case takes (weight_fast_path.h)
      const std::array<double, 4> mu = WeightingCoefficients(p);
      auto dp = [&](double b) { return (3 * mu[3] * b + 2 * mu[2]) * b + mu[1]; };
      rising_first += dp(ref.beta0) > 0 && dp(ref.beta_hi) < 0;
    }
    ASSERT_TRUE(ref.ok) << Describe(p);
    ASSERT_TRUE(fast.ok) << Describe(p);
    ASSERT_EQ(fast.beta0, ref.beta0);
    ASSERT_EQ(fast.beta_hi, ref.beta_hi);
    ASSERT_EQ(fast.num_maxima, ref.num_maxima) << Describe(p);
    const double rel = std::abs(fast.beta - ref.beta) / ref.beta;
    const double cond = Condition(p, ref.beta);
    if (cond <= 1e3) {  // well conditioned: the 1e−12
      worst_well = std::max(worst_well, rel);
      ASSERT_LE(rel, 1e-12) << Describe(p) << " fast=" << fast.beta << " reference=" << ref.beta << " cond=" << cond;
    } else {  // both solvers are at the rounding floor: compare both with the long-double root
      ++ill_conditioned;
      worst_ill = std::max(worst_ill, rel);
      const long double root = LongDoubleRoot(p, ref.beta);
      const double fast_error = static_cast<double>(std::abs(fast.beta - root) / root);
      const double ref_error = static_cast<double>(std::abs(ref.beta - root) / root);
      worst_oracle = std::max(worst_oracle, fast_error / (kEps * cond));
      ASSERT_LE(fast_error, std::max(1e-12, 16 * kEps * cond)) << Describe(p) << " cond=" << cond;
      ASSERT_LE(ref_error, std::max(1e-12, 16 * kEps * cond)) << Describe(p) << " cond=" << cond;
    }
    two_maxima += ref.num_maxima > 1;
    fast_iterations += fast.iterations;
    reference_iterations += ref.iterations;
  }
  // The sample reaches the "new information or outlier?" case of spec §5 often enough to test the
  // selection, and the ill-conditioned corner stays a corner.
  EXPECT_GT(two_maxima, 500);
  EXPECT_GT(rising_first, 500);
  EXPECT_LT(ill_conditioned, static_cast<int>(problems.size()) / 20);
  EXPECT_LT(fast_iterations, reference_iterations);
  RecordProperty("worst_relative_difference_well_conditioned", std::to_string(worst_well));
  std::printf(
      "fast vs reference over %zu problems (%d with two maxima, %d rising first): worst relative difference %.3g where "
      "cond <= 1e3; %d ill-conditioned (cond > 1e3): worst difference %.3g, worst fast error vs the "
      "long-double root %.3g eps*cond; iterations per call %.2f (fast) vs %.2f (reference)\n",
      problems.size(), two_maxima, rising_first, worst_well, ill_conditioned, worst_ill, worst_oracle,
      fast_iterations / double(problems.size()), reference_iterations / double(problems.size()));
}

TEST(WeightSolver, MatchesTheLongDoubleRootOnTheEstimatorsTypicalProblems) {
  // ν = 100 (forgetting 0.99), ξ_z = 1 − O(ρ/ν), Cauchy prediction errors with 5 % gross outliers.
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(0, 1);
  std::cauchy_distribution<double> c;
  for (int i = 0; i < 20000; ++i) {
    const int rho = 1 + i % 32;
    const double xi_z = 1 - rho * u(rng) / 100, e = c(rng) * (u(rng) < 0.05 ? 500 : 1);
    const WeightingProblem p{
        .nu = 100, .xi = xi_z - e * e, .xi_z = xi_z, .rho = rho, .k = i % 3 ? 1.0 : 3.0, .delta = 1};
    const WeightSolution s = SolveWeight(p);
    const long double root = LongDoubleRoot(p, s.beta);
    ASSERT_LE(static_cast<double>(std::abs(s.beta - root) / root), 4 * kEps) << Describe(p);
  }
}

TEST(WeightSolver, RootHasTinyResidualAndStaysInTheBracketOnExtremeProblems) {
  for (const WeightingProblem& p : ExtremeProblems(7, 100000)) {
    const WeightSolution s = SolveWeight(p);
    ASSERT_TRUE(s.ok) << Describe(p);
    ASSERT_GE(s.beta, s.beta0) << Describe(p);
    ASSERT_LE(s.beta, s.beta_hi) << Describe(p);
    ASSERT_GT(s.beta, 0);
    ASSERT_LT(s.beta, 1);
    if (s.beta != s.beta_hi) {
      std::array<double, 4> mu = WeightingCoefficients(p);
      ASSERT_LE(std::abs(EvalP(mu, s.beta)), 1e-12 * AbsTerms(mu, s.beta)) << Describe(p);
    }
  }
}

TEST(WeightSolver, ExactSpecialCases) {
  for (double k : {0.5, 1.0, 3.0, 1e5})
    for (int delta : {0, 1})
      for (int rho : {1, 4, 32}) {
        const double nu = NuHard(rho, k, delta) + 0.5;
        // h = 0: β = β_hi exactly [spec §4].
        WeightingProblem p{.nu = nu, .xi = 1, .xi_z = 1, .rho = rho, .k = k, .delta = delta};
        EXPECT_EQ(SolveWeight(p).beta, BetaHi(p));
        // ê = 0 with a regressor, and z = 0 with a non-zero y: the reference's root to 1e−13.
        const std::pair<double, double> cases[] = {{0.3, 0.3}, {-50.0, -50.0}, {0.9, 1.0}, {-1e9, 1.0}};
        for (auto [xi, xi_z] : cases) {
          p = {.nu = nu, .xi = xi, .xi_z = xi_z, .rho = rho, .k = k, .delta = delta};
          EXPECT_NEAR(SolveWeight(p).beta / SolveWeightReference(p).beta, 1, 1e-13) << Describe(p);
        }
      }
}

TEST(WeightSolver, SpecExamplesWithTwoLocalMaxima) {  // spec §5: the global maximum, not the nearest root
  WeightingProblem p{.nu = 12, .xi = -3e4, .xi_z = -400, .rho = 2, .k = 1, .delta = 1};
  WeightSolution s = SolveWeight(p);
  EXPECT_EQ(s.num_maxima, 2);
  EXPECT_NEAR(s.beta, 7.5437032e-6, 1e-13);
  p = {.nu = 7, .xi = -7.5e5, .xi_z = -8e3, .rho = 5, .k = 1, .delta = 1};
  s = SolveWeight(p);
  EXPECT_EQ(s.num_maxima, 2);
  EXPECT_NEAR(s.beta, 0.16646152, 1e-8);
}

TEST(WeightSolver, ConvergesWhenAnIterateLandsOnTheRootExactly) {
  // Met by the Cauchy estimator at ρ = 32 (kh_benchmark's stream, t = 131): ξ_z ≈ 1 − ρ is the normal
  // state there. The third iterate has P = +2e−16, becomes the lower bracket end, and its zero step must
  // end the search instead of triggering ~40 bisections.
  const WeightingProblem p{
      .nu = 82.485827516651426, .xi = -26.612085208868031, .xi_z = -26.608029358443186, .rho = 32, .k = 1, .delta = 1};
  const WeightSolution fast = SolveWeight(p);
  EXPECT_LE(fast.iterations, 4);
  EXPECT_NEAR(fast.beta / SolveWeightReference(p).beta, 1, 1e-14);
  EXPECT_NEAR(fast.beta / static_cast<double>(LongDoubleRoot(p, fast.beta)), 1, 4 * kEps);
}

TEST(WeightSolver, OverflowingCoefficientsFallBackToTheScaledReference) {
  // |μ3| ~ ν·|ξξ_z| ~ 1e150 would overflow P'² unscaled.
  const WeightingProblem p{.nu = 9, .xi = -1e75, .xi_z = -1e74, .rho = 3, .k = 1, .delta = 1};
  const WeightSolution fast = SolveWeight(p), ref = SolveWeightReference(p);
  ASSERT_TRUE(fast.ok);
  EXPECT_NEAR(fast.beta / ref.beta, 1, 1e-12);
  EXPECT_GE(fast.beta, fast.beta0);
  EXPECT_LE(fast.beta, fast.beta_hi);
}

}  // namespace
}  // namespace ident::approx
