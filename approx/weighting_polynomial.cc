#include "approx/weighting_polynomial.h"

#include "approx/weight_fast_path.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace ident::approx {
namespace {

using internal::Coefficients;
using internal::EvalDP;
using internal::EvalP;
using internal::HouseholderRoot;
using internal::SmallRootGuess;

// Root of P in (a, b) with P(a) > 0 > P(b): Newton from the midpoint, replaced by bisection whenever
// a step leaves the current bracket; stop when |Δβ| ≤ 4e−16·β [spec §5].
// `guess` (if inside the bracket) is the first iterate.
double BracketedRoot(const std::array<double, 4>& mu, double a, double b, double guess, int& iterations) {
  double x = (guess > a && guess < b) ? guess : 0.5 * (a + b);
  for (int iter = 0; iter < 400; ++iter) {
    ++iterations;
    const double fx = EvalP(mu, x);
    if (fx == 0) return x;
    if (fx > 0)
      a = x;
    else
      b = x;  // keep P(a) > 0 > P(b)
    const double dfx = EvalDP(mu, x);
    double next = (dfx != 0) ? x - fx / dfx : std::numeric_limits<double>::quiet_NaN();
    if (!(next > a && next < b)) next = 0.5 * (a + b);  // Newton left the bracket (or NaN): bisect
    const double step = std::abs(next - x);
    x = next;
    if (step <= 4e-16 * x || b - a <= 4e-16 * b) break;
  }
  return x;
}

// First iterate of the reference: the large-ν limit νβ ≈ b0 = (k+1)/(k + ê²/D_y), ê²/D_y = ξ_z − ξ
// [spec §7a].
double AsymptoticGuess(const WeightingProblem& p) { return AsymptoticGuessInline(p); }

}  // namespace

double NuHard(int rho, double k, int delta) {
  return std::max({static_cast<double>(rho + delta - 1), (k + 3 - delta) / k, rho / (k + 1)});
}

double NuRobust(int rho, double k, int delta) { return rho + k + delta - 1; }

double Beta0(const WeightingProblem& p) { return Beta0Inline(p); }

double BetaHi(const WeightingProblem& p) { return BetaHiInline(p); }

std::array<double, 4> WeightingCoefficients(const WeightingProblem& p) { return Coefficients(p); }

double WeightElasticity(const WeightingProblem& p, double beta) {
  return WeightElasticityInline(p, WeightConstants(p), beta);
}

double LogH0(const WeightingProblem& p, double beta) {
  const double kappa = (p.k + 1) / 2, n = p.nu - p.delta;
  return kappa * (std::log(beta) + (p.nu - 1) * std::log1p(-beta)) - (n + 1) / 2 * std::log1p(-beta) -
         (n - p.rho + 2) / 2 * std::log1p(-beta * p.xi) + (n - p.rho + 1) / 2 * std::log1p(-beta * p.xi_z);
}

double LogHFull(const WeightingProblem& p, double beta) {
  const double b0 = Beta0(p);
  if (beta >= b0) return LogH0(p, beta);
  // β < β0: essinf = [(1−βr)^ν/(1−r)]^κ, r = min(0, ξ); LogH0 omits κ[ν log ν + (1−ν) log(ν−1)] [spec §3].
  const double kappa = (p.k + 1) / 2, n = p.nu - p.delta, r = std::min(0.0, p.xi);
  const double log_essinf = kappa * (p.nu * std::log1p(-beta * r) - std::log1p(-r)) -
                            kappa * (p.nu * std::log(p.nu) + (1 - p.nu) * std::log(p.nu - 1));
  const double log_integral = -(n + 1) / 2 * std::log1p(-beta) - (n - p.rho + 2) / 2 * std::log1p(-beta * p.xi) +
                              (n - p.rho + 1) / 2 * std::log1p(-beta * p.xi_z);
  return log_essinf + log_integral;
}

namespace {

// The pieces of spec §5: [β0, β_hi] split at the real roots of P' in (β0, β_hi); every + → − sign
// change of P on a piece [lo, hi] gives a candidate root(lo, hi, P(lo), P(hi)); the candidate with the
// largest log H0 wins. `mu` may be scaled by any positive factor.
template <class Root>
void SolveOnPieces(const WeightingProblem& p, const std::array<double, 4>& mu, WeightSolution& s, Root root) {
  // Break points: β0, β_hi and the real roots of P' = μ1 + 2μ2β + 3μ3β² inside (β0, β_hi).
  std::array<double, 4> pts{s.beta0, s.beta_hi, 0, 0};
  int npts = 2;
  const double A = 3 * mu[3], B = 2 * mu[2], C = mu[1];
  auto add = [&](double x) {
    if (x > s.beta0 && x < s.beta_hi) pts[npts++] = x;
  };
  if (A == 0) {
    if (B != 0) add(-C / B);
  } else {
    const double disc = B * B - 4 * A * C;
    if (disc >= 0) {
      const double q = -(B + std::copysign(std::sqrt(disc), B)) / 2;  // stable quadratic formula
      if (q != 0) {
        add(q / A);
        add(C / q);
      }
    }
  }
  for (int i = 1; i < npts; ++i)  // insertion sort of at most 4 points
    for (int j = i; j > 0 && pts[j] < pts[j - 1]; --j) std::swap(pts[j], pts[j - 1]);

  std::array<double, 4> candidates{};
  int nc = 0;
  double pa = EvalP(mu, pts[0]);
  for (int i = 0; i + 1 < npts; ++i) {
    const double pb = EvalP(mu, pts[i + 1]);
    if (pa > 0 && pb < 0) candidates[nc++] = root(pts[i], pts[i + 1], pa, pb);
    pa = pb;
  }
  if (EvalP(mu, s.beta_hi) >= 0) candidates[nc++] = s.beta_hi;  // h = 0 (or rounding at the upper end)
  if (nc == 0) {
    // P(β0) ≤ 0 can only come from rounding (P(β0) > 0 for ν > ν_hard): the maximum is at β0.
    s.ok = EvalP(mu, s.beta0) <= 0 && s.beta0 <= s.beta_hi;
    candidates[nc++] = s.beta0;
  }
  // Several local maxima: keep the one with the largest log H0 (only then is log H0 evaluated).
  s.num_maxima = nc;
  s.beta = candidates[0];
  s.smallest_maximum = *std::min_element(candidates.begin(), candidates.begin() + nc);
  if (nc > 1) {
    double best_value = LogH0(p, s.beta);
    for (int i = 1; i < nc; ++i) {
      const double v = LogH0(p, candidates[i]);
      if (v > best_value) best_value = v, s.beta = candidates[i];
    }
  }
}

// A solution holding only the bracket [β0, β_hi] of spec §4.
WeightSolution Bracket(const WeightingProblem& p) {
  WeightSolution s;
  s.beta0 = Beta0(p);
  s.beta_hi = BetaHi(p);
  return s;
}

// h = 0 (ξ = ξ_z = 1): P(β_hi) = 0 analytically and β = β_hi exactly [spec §4].
bool IsZeroData(const WeightingProblem& p) { return p.xi == 1 && p.xi_z == 1; }
WeightSolution ZeroDataSolution(WeightSolution s) {
  s.beta = s.smallest_maximum = s.beta_hi;
  s.num_maxima = 1;
  return s;
}

}  // namespace

WeightSolution SolveWeightReference(const WeightingProblem& p) {
  WeightSolution s = Bracket(p);
  if (IsZeroData(p)) return ZeroDataSolution(s);
  std::array<double, 4> mu = Coefficients(p);
  double scale = 0;
  for (double m : mu) scale = std::max(scale, std::abs(m));
  for (double& m : mu) m /= scale;  // does not change the roots
  const double guess = AsymptoticGuess(p);
  SolveOnPieces(p, mu, s,
                [&](double a, double b, double, double) { return BracketedRoot(mu, a, b, guess, s.iterations); });
  return s;
}

WeightSolution SolveWeight(const WeightingProblem& p) {
  WeightSolution s;
  if (internal::SolveWeightCommon(p, WeightConstants(p), s)) return s;  // the usual case (weight_fast_path.h)
  s = Bracket(p);
  if (IsZeroData(p)) return ZeroDataSolution(s);
  std::array<double, 4> mu = Coefficients(p);
  // Scaling changes neither the roots nor the steps; it only guards the squares below against
  // overflow (|ξξ_z| ~ 1e28 is routine [spec §5]; 1e60 is not).
  const double biggest =
      std::max(std::max(std::abs(mu[0]), std::abs(mu[1])), std::max(std::abs(mu[2]), std::abs(mu[3])));
  if (!(biggest < 1e60)) {
    if (!std::isfinite(biggest)) return SolveWeightReference(p);
    for (double& m : mu) m /= biggest;
  }
  const double a = s.beta0, b = s.beta_hi;
  double guess = SmallRootGuess(mu);
  if (!(guess > a && guess < b)) guess = AsymptoticGuess(p);  // e.g. a novel regressor (ξ_z ≪ 0)
  // P strictly decreasing on [a, b] ⇔ P' ≤ 0 there. P' = C + Bβ + Aβ² is ≤ 0 at both ends, and has a
  // positive maximum inside only if it is concave with its vertex inside (P'' = B + 2Aβ falls from > 0
  // at a to < 0 at b) and a positive discriminant B² − 4AC. If not, with P(a) > 0 > P(b) [spec §4] the
  // root is unique: no square root, no pieces, no log H0.
  const double A = 3 * mu[3], B = 2 * mu[2], C = mu[1];
  const double dpa = (A * a + B) * a + C, dpb = (A * b + B) * b + C;
  const bool interior_max = B + 2 * A * a > 0 && B + 2 * A * b < 0 && B * B - 4 * A * C > 0;
  if (dpa <= 0 && dpb <= 0 && !interior_max && EvalP(mu, a) > 0 && EvalP(mu, b) < 0) {
    s.beta = s.smallest_maximum = HouseholderRoot(mu, a, b, guess, s.iterations);
    s.num_maxima = 1;
    return s;
  }
  // Otherwise the pieces of spec §5 (P' has roots inside, or rounding at an end); each piece starts at
  // the asymptote if it lies inside, else at its regula-falsi point.
  SolveOnPieces(p, mu, s, [&](double lo, double hi, double plo, double phi) {
    const double x = (guess > lo && guess < hi) ? guess : lo + plo / (plo - phi) * (hi - lo);
    return HouseholderRoot(mu, lo, hi, x, s.iterations);
  });
  return s;
}

}  // namespace ident::approx
