#include "models/truncated_bivariate_normal.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

#include <boost/math/distributions/normal.hpp>
#include <boost/math/quadrature/gauss_kronrod.hpp>
#include <boost/math/special_functions/owens_t.hpp>

#include "models/measurement.h"

namespace ident::models {
namespace {

constexpr double kPlusInfinity = std::numeric_limits<double>::infinity();
constexpr double kNotANumber = std::numeric_limits<double>::quiet_NaN();

// log of the integrand φ(y) Q((h − ρy)/s) of P(X > h, Y > k) = ∫_k^∞ φ(y) Q((h − ρy)/s) dy.
double LogIntegrand(double y, double h, double rho, double s) {
  return LogNormalDensity(y) + LogNormalTail((h - rho * y) / s);
}

// d/dy of LogIntegrand: −y + (ρ/s) λ(z), z = (h − ρy)/s, λ = φ/Q the normal hazard. Decreasing in y
// (the integrand is log-concave with curvature ≤ −1).
double LogIntegrandSlope(double y, double h, double rho, double s) {
  const double z = (h - rho * y) / s;
  return -y + rho / s * std::exp(LogNormalDensity(z) - LogNormalTail(z));
}

// Φ2(a, b; ρ) = P(X ≤ a, Y ≤ b) by Owen's T (Owen 1956, eq. (2.1)):
//   Φ2 = ½Φ(a) + ½Φ(b) − T(a, α_a) − T(b, α_b) − β,  α_a = (b − ρa)/(a s),  α_b = (a − ρb)/(b s),
//   β = 0 if ab > 0, else ½   (a, b ≠ 0, s = √(1 − ρ²)).
// Absolute error ≈ 1e-16 (the terms are O(1) and cancel when Φ2 is small).
double OwenBivariateCdf(double a, double b, double rho, double s) {
  const double alpha_a = (b - rho * a) / (a * s), alpha_b = (a - rho * b) / (b * s);
  const double beta = a * b > 0 ? 0.0 : 0.5;
  // Evaluated in double (no promotion to long double, which doubles the cost of a wedge refit).
  using Policy = boost::math::policies::policy<boost::math::policies::promote_double<false>>;
  const boost::math::normal_distribution<double, Policy> unit;
  return 0.5 * boost::math::cdf(unit, a) + 0.5 * boost::math::cdf(unit, b) -
         boost::math::owens_t(a, alpha_a, Policy()) - boost::math::owens_t(b, alpha_b, Policy()) - beta;
}

// Below this probability the closed form's absolute error (≈ 1e-16) exceeds a relative 1e-10: quadrature.
constexpr double kClosedFormFloor = 1e-5;

}  // namespace

double LogUpperOrthantProbability(double h, double k, double rho) {
  if (std::isnan(h) || std::isnan(k) || !(std::abs(rho) < 1)) return kNotANumber;
  if (h == kPlusInfinity || k == kPlusInfinity) return -kPlusInfinity;
  if (h == -kPlusInfinity) return LogNormalTail(k);
  if (k == -kPlusInfinity) return LogNormalTail(h);
  const double s = std::sqrt((1 - rho) * (1 + rho));
  // P(X > h, Y > k) = Φ2(−h, −k; ρ): Owen's T closed form where it keeps 1e-10 relative accuracy
  // (far cheaper than adaptive quadrature); the log-space quadrature below for the tails.
  if (h != 0 && k != 0) {
    const double p = OwenBivariateCdf(-h, -k, rho, s);
    if (p >= kClosedFormFloor && p <= 1) return std::log(p);
  }
  return LogUpperOrthantProbabilityByQuadrature(h, k, rho);
}

double LogUpperOrthantProbabilityByQuadrature(double h, double k, double rho) {
  if (std::isnan(h) || std::isnan(k) || !(std::abs(rho) < 1)) return kNotANumber;
  if (h == kPlusInfinity || k == kPlusInfinity) return -kPlusInfinity;
  if (h == -kPlusInfinity) return LogNormalTail(k);
  if (k == -kPlusInfinity) return LogNormalTail(h);
  const double s = std::sqrt((1 - rho) * (1 + rho));
  // Mode y* of the log-concave integrand on [k, ∞): bracket, then bisection on the decreasing slope.
  double mode = k;
  if (LogIntegrandSlope(k, h, rho, s) > 0) {
    double lo = k, step = 1, hi = k + step;
    for (int i = 0; i < 200 && LogIntegrandSlope(hi, h, rho, s) > 0; ++i) lo = hi, step *= 2, hi = k + step;
    for (int i = 0; i < 200 && hi - lo > 1e-12 * (1 + std::abs(lo)); ++i) {
      const double mid = 0.5 * (lo + hi);
      (LogIntegrandSlope(mid, h, rho, s) > 0 ? lo : hi) = mid;
    }
    mode = 0.5 * (lo + hi);
  }
  const double peak = LogIntegrand(mode, h, rho, s);
  if (!std::isfinite(peak)) return -kPlusInfinity;
  // Curvature ≤ −1, so the integrand is below e^(−800) of its peak beyond ±40 of the mode. Cut at the
  // mode and at the edge of the Q factor (z = 0, width s/|ρ|).
  std::array<double, 4> cuts{std::max(k, mode - 40), mode, mode + 40, kNotANumber};
  int n = 3;
  if (rho != 0) {
    const double edge = h / rho;
    if (edge > cuts[0] && edge < cuts[2] && edge != mode) cuts[n++] = edge;
  }
  std::sort(cuts.begin(), cuts.begin() + n);
  using GK = boost::math::quadrature::gauss_kronrod<double, 61>;
  auto f = [&](double y) { return std::exp(LogIntegrand(y, h, rho, s) - peak); };
  double sum = 0;
  for (int i = 0; i + 1 < n; ++i) {
    // Each piece mapped onto [−1, 1]: Boost's recursion compares the unscaled error estimate with the
    // scaled integral, so a narrow piece would otherwise demand an unreachable relative accuracy.
    const double half = 0.5 * (cuts[i + 1] - cuts[i]), mid = 0.5 * (cuts[i + 1] + cuts[i]);
    if (half > 0) sum += half * GK::integrate([&](double t) { return f(mid + half * t); }, -1.0, 1.0, 15, 1e-13);
  }
  return peak + std::log(sum);
}

TruncatedBivariateMoments TruncatedBivariateNormalMoments(const Eigen::Vector2d& mean,
                                                          const Eigen::Matrix2d& covariance,
                                                          const Eigen::Vector2d& bounds, const Eigen::Vector2d& sides) {
  TruncatedBivariateMoments out;
  if (!mean.allFinite() || !covariance.allFinite() || bounds.hasNaN()) return out;
  if (std::abs(sides(0)) != 1 || std::abs(sides(1)) != 1) return out;
  if (!(covariance(0, 0) > 0) || !(covariance(1, 1) > 0)) return out;
  const Eigen::Vector2d sd(std::sqrt(covariance(0, 0)), std::sqrt(covariance(1, 1)));
  // Standardise: w_i = side_i (s_i − μ_i)/σ_i, region w_i > side_i (b_i − μ_i)/σ_i, corr(w) = side_1 side_2 ρ.
  const double rho = sides(0) * sides(1) * 0.5 * (covariance(0, 1) + covariance(1, 0)) / (sd(0) * sd(1));
  if (!(std::abs(rho) < 1 - 1e-12)) return out;
  const double h = sides(0) * (bounds(0) - mean(0)) / sd(0);
  const double k = sides(1) * (bounds(1) - mean(1)) / sd(1);
  const double log_l = LogUpperOrthantProbability(h, k, rho);
  // Mass below the smallest normal double: the reading is impossible under the prior to double precision.
  if (!std::isfinite(log_l) || log_l < std::log(std::numeric_limits<double>::min())) return out;
  const double s = std::sqrt((1 - rho) * (1 + rho));
  // Ratios to L of A_h = φ(h) Q((k − ρh)/s), A_k = φ(k) Q((h − ρk)/s) and f = φ2(h, k; ρ) (zero at −∞).
  const bool fin_h = std::isfinite(h), fin_k = std::isfinite(k);
  const double r_h =
      fin_h ? std::exp(LogNormalDensity(h) + (fin_k ? LogNormalTail((k - rho * h) / s) : 0.0) - log_l) : 0.0;
  const double r_k =
      fin_k ? std::exp(LogNormalDensity(k) + (fin_h ? LogNormalTail((h - rho * k) / s) : 0.0) - log_l) : 0.0;
  const double r_f =
      fin_h && fin_k
          ? std::exp(-(h * h - 2 * rho * h * k + k * k) / (2 * s * s) - std::log(2 * std::numbers::pi * s) - log_l)
          : 0.0;
  const double h_rh = fin_h ? h * r_h : 0.0, k_rk = fin_k ? k * r_k : 0.0;
  const double ex = r_h + rho * r_k, ey = r_k + rho * r_h;                      // E[X], E[Y]
  const double vx = 1 + h_rh + rho * rho * k_rk + rho * s * s * r_f - ex * ex;  // Var X
  const double vy = 1 + k_rk + rho * rho * h_rh + rho * s * s * r_f - ey * ey;  // Var Y
  const double cxy = rho + rho * h_rh + rho * k_rk + s * s * r_f - ex * ey;     // Cov(X, Y)
  if (!(vx > 0) || !(vy > 0) || !std::isfinite(cxy)) return out;
  out.log_probability = log_l;
  out.mean << mean(0) + sides(0) * sd(0) * ex, mean(1) + sides(1) * sd(1) * ey;
  out.covariance << covariance(0, 0) * vx, sides(0) * sides(1) * sd(0) * sd(1) * cxy,
      sides(0) * sides(1) * sd(0) * sd(1) * cxy, covariance(1, 1) * vy;
  out.ok = out.mean.allFinite() && out.covariance.allFinite();
  return out;
}

}  // namespace ident::models
