// The common case of SolveWeight (approx/weighting_polynomial.h), inline, for the estimators' update:
// the weighting cubic P has one sign change on the bracket [β0, β_hi] of spec §4 (it decreases there, or rises
// and then falls), so its root there is the unique maximum of log H0 and hence the maximin weight β(t) of spec §5, found by Householder
// iterations of order 3 inside a shrinking bracket from the small-root start, or from the large-ν asymptote
// when that start falls outside the bracket (no log H0, no square root, no pieces). SolveWeight itself starts
// with this very function, so the estimators' inline call and the library call return the same bits; every
// other case (h = 0, more than one sign change possible, huge coefficients) is left to SolveWeight's general path.
//
// Why inline: on the estimators' data the update is limited by how many instructions the out-of-order
// core can hold while the back substitution, the weight and the update of d wait on one another, not
// by the length of the weight's own dependency chain (bench/kh_benchmark.cc, docs/explanation/karny-hangos-estimator.md): the call,
// the returned struct and the second, exact monotonicity test cost as much as the iteration.
//
//   Monotonicity [spec §5]: P'(β) = μ1 + 2μ2β + 3μ3β² ≤ μ1 + 2 max(μ2, 0) β_hi + 3 max(μ3, 0) β_hi² on
//   [0, β_hi] ⊇ [β0, β_hi]; if that bound is negative (with a margin for its rounding) P decreases on
//   the bracket. Otherwise the exact test: P' ≤ 0 at both ends and no interior maximum of P' above 0 —
//   or P' > 0 at β0 and < 0 at β_hi, where P rises, then falls (one root of P' inside), so that P(β0) > 0 > P(β_hi)
//   still leaves one sign change of P, the only candidate of spec §5's pieces.
//
// Example:
//   ident::approx::WeightConstants c;                      // kept by the estimator
//   if (problem.nu != c.nu) c.Set(problem);                // ν(t) settles under forgetting
//   ident::approx::WeightSolution s = ident::approx::SolveWeightInline(problem, c);   // == SolveWeight(problem)
#pragma once

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>

#include "approx/weighting_polynomial.h"

namespace ident::approx {

// β0 = 1/(ν − (ν−1)min(0, ξ)) and β_hi = (k+1)/(kν+δ−2), the bracket of spec §4.
inline double Beta0Inline(const WeightingProblem& p) { return 1 / (p.nu - (p.nu - 1) * std::min(0.0, p.xi)); }
inline double BetaHiInline(const WeightingProblem& p) { return (p.k + 1) / (p.k * p.nu + p.delta - 2); }
// The root's large-ν asymptote (k+1)/(ν(k + u)), u = ξ_z − ξ = ê²/D_y [spec §7a]: the start when the
// small-root guess falls outside the bracket.
inline double AsymptoticGuessInline(const WeightingProblem& p) { return (p.k + 1) / (p.nu * (p.k + (p.xi_z - p.xi))); }

// The parts of μ1, μ2, μ3 and of β_hi that depend only on (ν, ρ, k, δ), formed exactly as in
// spec §4's coefficients (the same operations in the same order, so the same bits). Under forgetting
// ν(t) settles at its fixed point, so an estimator forms them once instead of at every step.
struct WeightConstants {
  double nu = std::numeric_limits<double>::quiet_NaN();  // the ν they were formed for
  double mu1_0 = 0, mu1_xi = 0, mu1_xz = 0;              // μ1 = −mu1_0 + mu1_xi ξ − mu1_xz ξ_z
  double mu2_xi = 0, mu2_xz = 0, k = 0;                  // μ2 = mu2_xi ξ + mu2_xz ξ_z + k ξ ξ_z
  double mu3 = 0;                                        // μ3 = mu3 ξ ξ_z
  double beta_hi = 0;                                    // (k+1)/(kν+δ−2)

  WeightConstants() = default;
  explicit WeightConstants(const WeightingProblem& p) { Set(p); }
  void Set(const WeightingProblem& p) {
    const double nu_ = p.nu, k_ = p.k, d = p.delta, rho = p.rho;
    nu = nu_;
    mu1_0 = k_ * nu_ + d - 1;
    mu1_xi = nu_ - d - rho + 1 - k_;
    mu1_xz = nu_ - d - rho + 2 + k_;
    mu2_xi = (k_ - 1) * nu_ + 2 * d + rho - 3;
    mu2_xz = (k_ + 1) * nu_ - rho;
    k = k_;
    mu3 = 2 - k_ * nu_ - d;
    beta_hi = (k_ + 1) / (k_ * nu_ + d - 2);
  }
};

namespace internal {

// c ? x : y without a branch (bit masks: a ?: on doubles is compiled back into a jump, and the sign of
// P at the start is a coin flip on the estimators' data).
inline double Select(bool c, double x, double y) {
  const std::uint64_t mask = -static_cast<std::uint64_t>(c);
  return std::bit_cast<double>((std::bit_cast<std::uint64_t>(x) & mask) | (std::bit_cast<std::uint64_t>(y) & ~mask));
}

// P(β) and P'(β) by Horner.
inline double EvalP(const std::array<double, 4>& mu, double beta) {
  return ((mu[3] * beta + mu[2]) * beta + mu[1]) * beta + mu[0];
}
inline double EvalDP(const std::array<double, 4>& mu, double beta) {
  return (3 * mu[3] * beta + 2 * mu[2]) * beta + mu[1];
}
// The same by Estrin's scheme, (μ0 + μ1β) + (μ2 + μ3β)β²: two multiply-add levels instead of three
// (the iteration's dependency chain; same error bound).
inline double EvalPEstrin(const std::array<double, 4>& mu, double beta) {
  return (mu[1] * beta + mu[0]) + (mu[3] * beta + mu[2]) * (beta * beta);
}
inline double EvalDPEstrin(const std::array<double, 4>& mu, double beta) {
  return (2 * mu[2] * beta + mu[1]) + 3 * mu[3] * (beta * beta);
}

// μ0..μ3 of spec §4 (unscaled), from the constants of p.nu.
inline std::array<double, 4> Coefficients(const WeightingProblem& p, const WeightConstants& c) {
  const double xi = p.xi, xz = p.xi_z;
  return {c.k + 1, -c.mu1_0 + c.mu1_xi * xi - c.mu1_xz * xz, c.mu2_xi * xi + c.mu2_xz * xz + c.k * xi * xz,
          c.mu3 * xi * xz};
}

// μ0..μ3 of spec §4 (unscaled).
inline std::array<double, 4> Coefficients(const WeightingProblem& p) {
  const double nu = p.nu, k = p.k, d = p.delta, rho = p.rho, xi = p.xi, xz = p.xi_z;
  return {k + 1,                                                                            // μ0
          -(k * nu + d - 1) + (nu - d - rho + 1 - k) * xi - (nu - d - rho + 2 + k) * xz,    // μ1
          ((k - 1) * nu + 2 * d + rho - 3) * xi + ((k + 1) * nu - rho) * xz + k * xi * xz,  // μ2
          (2 - k * nu - d) * xi * xz};                                                      // μ3
}

// Householder's order-3 step from β = 0, where the derivatives are the coefficients themselves
// (f = μ0, f' = μ1, f'' = 2μ2, f''' = 6μ3): no Horner, one division; accurate to O(1/ν³) relative
// on ordinary samples (the root is ~ (k+1)/(ν(k + ê²/D_y)) [spec §7a]).
inline double SmallRootGuess(const std::array<double, 4>& mu) {
  const double f = mu[0], df = mu[1], d2f = 2 * mu[2], d3f = 6 * mu[3];
  const double ff = f * d2f;
  return -f * (6 * df * df - 3 * ff) / ((6 * df * df - 6 * ff) * df + f * f * d3f);
}

// Root of P in (a, b) with P(a) > 0 > P(b) and P monotone on [a, b]. P is a cubic, so its Taylor
// series at x is exact: each iterate takes Householder's step of order 3 (quartic convergence)
//     Δ = −f(6f'² − 3ff'') / (6f'³ − 6ff'f'' + f²f'''),
// replaced by bisection whenever it leaves the current bracket (which shrinks at every iterate,
// keeping P(a) > 0 > P(b)); never an unbracketed step. The error after a step is ≈ K·Δ⁴ with
// K = |f''|·|3f''² − 4f'f'''|/(24|f'|³): stop as soon as K·Δ⁴ ≤ 1e−16·β, or the step itself is
// ≤ 1e−16·β, or the bracket is 4e−16·β wide. `x` (if inside the bracket) is the first iterate, else
// the midpoint.
#if defined(__GNUC__)
__attribute__((always_inline))
#endif
inline double
HouseholderRoot(const std::array<double, 4>& mu, double a, double b, double x, int& iterations) {
  if (!(x > a && x < b)) x = 0.5 * (a + b);
  const double d3f = 6 * mu[3];
  for (int iter = 0; iter < 400; ++iter) {
    ++iterations;
    const double f = EvalPEstrin(mu, x);
    if (f == 0) return x;
    const bool positive = f > 0;  // keep P(a) > 0 > P(b)
    a = Select(positive, x, a);
    b = Select(positive, b, x);
    const double df = EvalDPEstrin(mu, x);
    const double d2f = d3f * x + 2 * mu[2];
    const double ff = f * d2f;
    const double next = x - f * (6 * df * df - 3 * ff) / ((6 * df * df - 6 * ff) * df + f * f * d3f);
    if (std::abs(next - x) <= 1e-16 * x) return next;  // at the root to rounding (x may now be a bracket end)
    if (!(next > a && next < b)) {                     // the step left the bracket (or NaN): bisect
      x = 0.5 * (a + b);
      if (b - a <= 4e-16 * b) break;
      continue;
    }
    const double step = next - x, step2 = step * step;
    x = next;
    if (std::abs(d2f * (3 * d2f * d2f - 4 * df * d3f)) * (step2 * step2) <= 24e-16 * std::abs(df * df * df) * x ||
        b - a <= 4e-16 * b)
      break;
  }
  return x;
}

// The common case (see the header comment): fills s (β, β0, β_hi, num_maxima = 1, iterations) and
// returns true, or returns false (s partly written) when SolveWeight's general path must decide.
// `c` must have been formed for p (c.nu == p.nu, same ρ, k, δ). Forced inline: GCC otherwise keeps it
// out of line, and the call sits on the update's critical path (see the header comment).
#if defined(__GNUC__)
__attribute__((always_inline))
#endif
inline bool
SolveWeightCommon(const WeightingProblem& p, const WeightConstants& c, WeightSolution& s) {
  const double a = Beta0Inline(p), b = c.beta_hi;
  s.beta0 = a;
  s.beta_hi = b;
  if (p.xi == 1 && p.xi_z == 1) return false;  // h = 0: β = β_hi exactly [spec §4]
  const std::array<double, 4> mu = Coefficients(p, c);
  // The squares in the iteration stay finite for |μ| < 1e60 (|ξξ_z| ~ 1e28 is routine [spec §5]).
  const double biggest =
      std::max(std::max(std::abs(mu[0]), std::abs(mu[1])), std::max(std::abs(mu[2]), std::abs(mu[3])));
  if (!(biggest < 1e60)) return false;
  double guess = SmallRootGuess(mu);
  if (!(guess > a && guess < b)) guess = AsymptoticGuessInline(p);  // e.g. a novel regressor (ξ_z ≪ 0)
  // P decreasing on [a, b] (header comment); the bound's rounding is below 1e−14·|μ1| when it is negative.
  const double A = 3 * mu[3], B = 2 * mu[2], C = mu[1];
  bool one_crossing = C + std::max(B, 0.0) * b + std::max(A, 0.0) * (b * b) < 1e-14 * C;
  if (!one_crossing) {
    const double dpa = (A * a + B) * a + C, dpb = (A * b + B) * b + C;
    const bool interior_max = B + 2 * A * a > 0 && B + 2 * A * b < 0 && B * B - 4 * A * C > 0;
    // Rising, then falling: P' > 0 at a and < 0 at b (beyond the rounding of its terms) has exactly one root
    // inside, so P(a) > 0 > P(b) leaves one sign change of P, on the falling piece — spec §5's only candidate.
    const double margin_a = 1e-13 * (std::abs(A * a * a) + std::abs(B * a) + std::abs(C));
    const double margin_b = 1e-13 * (std::abs(A * b * b) + std::abs(B * b) + std::abs(C));
    one_crossing = (dpa <= 0 && dpb <= 0 && !interior_max) || (dpa > margin_a && dpb < -margin_b);
  }
  if (!(one_crossing && EvalP(mu, a) > 0 && EvalP(mu, b) < 0)) return false;
  s.beta = HouseholderRoot(mu, a, b, guess, s.iterations);
  s.num_maxima = 1;
  return true;
}

}  // namespace internal

// WeightElasticity (approx/weighting_polynomial.h) from the constants of p.nu, inline: WeightElasticity itself
// calls it, so both return the same bits. ∂μ1/∂ξ = mu1_xi, ∂μ2/∂ξ = mu2_xi + kξ_z, ∂μ3/∂ξ = mu3·ξ_z [spec §4].
inline double WeightElasticityInline(const WeightingProblem& p, const WeightConstants& c, double beta) {
  const std::array<double, 4> mu = internal::Coefficients(p, c);
  const double dp_dbeta = (3 * mu[3] * beta + 2 * mu[2]) * beta + mu[1];
  const double dp_dxi = ((c.mu3 * p.xi_z * beta + (c.mu2_xi + c.k * p.xi_z)) * beta + c.mu1_xi) * beta;
  return 2 * (p.xi_z - p.xi) * dp_dxi / dp_dbeta;
}

// SolveWeight with its common case inline (same results, bit for bit); `c` as for SolveWeightCommon.
// Forced inline as well, so that the solution stays in registers (not returned through memory).
#if defined(__GNUC__)
__attribute__((always_inline))
#endif
inline WeightSolution
SolveWeightInline(const WeightingProblem& p, const WeightConstants& c) {
  WeightSolution s;
  if (internal::SolveWeightCommon(p, c, s)) return s;
  return SolveWeight(p);
}

}  // namespace ident::approx
