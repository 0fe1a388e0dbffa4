// Moments of a bivariate normal restricted to a quadrant (Tallis 1961), the measurement update of a
// reading that constrains a correlated pair s = (s1, s2) to half-lines, e.g. the threshold sensor's
// crossing reading s1 = x1(k−1) < T ≤ x1(k) = s2 (studies/mems/crossing_reading.h).
//
// Provides:
//   LogUpperOrthantProbability(h, k, ρ) log P(X > h, Y > k) for standard normals with correlation ρ:
//                                      Owen's T closed form (Boost.Math owens_t) when P ≥ 1e-5, else
//                                      LogUpperOrthantProbabilityByQuadrature: adaptive Gauss–Kronrod
//                                      quadrature of φ(y) Q((h − ρy)/√(1−ρ²)) over y > k, scaled at the
//                                      mode (accurate far into the tails; much slower)
//   TruncatedBivariateNormalMoments    N(μ, Σ) restricted to {side_i (s_i − b_i) > 0, i = 1, 2}
//                                      (side_i = ±1, b_i may be −∞·side_i for "no bound"): log mass, mean,
//                                      covariance. The region is an intersection of half-planes, so the
//                                      restricted density is log-concave [1, Thm 2 applies].
//
// Formulas (standardised X, Y, correlation ρ, s = √(1−ρ²), region X > h, Y > k, L = P(region)):
//   A_h = φ(h) Q((k − ρh)/s),  A_k = φ(k) Q((h − ρk)/s),  f = φ2(h, k; ρ)
//   L E[X]  = A_h + ρ A_k                       L E[Y]  = A_k + ρ A_h
//   L E[X²] = L + h A_h + ρ² k A_k + ρ s² f     L E[Y²] = L + k A_k + ρ² h A_h + ρ s² f
//   L E[XY] = ρ L + ρ h A_h + ρ k A_k + s² f
// (Stein's identity E[X g] = E[∂g/∂x] + ρ E[∂g/∂y] applied to g = 1, x, y on the quadrant; Tallis,
// J. R. Stat. Soc. B 23 (1961), eqs. for the bivariate case.) All ratios A/L, f/L are formed in log space.
//
// Example:
//   // s1 = x1(k−1), s2 = x1(k) jointly normal; the crossing 0 → +1 of a threshold at 1: s1 < 1 ≤ s2.
//   auto t = ident::models::TruncatedBivariateNormalMoments(mu, Sigma, Eigen::Vector2d(1, 1),
//                                                          Eigen::Vector2d(-1, +1));
//   if (t.ok) { /* t.mean, t.covariance, exp(t.log_probability) */ }
//
// [1] T. Henningsson, K. J. Åström, "Log-concave Observers", MTNS 2006.
#pragma once

#include <limits>

#include <Eigen/Core>

namespace ident::models {

struct TruncatedBivariateMoments {
  double log_probability = std::numeric_limits<double>::quiet_NaN();  // log P(region) under N(μ, Σ)
  Eigen::Vector2d mean = Eigen::Vector2d::Constant(std::numeric_limits<double>::quiet_NaN());
  Eigen::Matrix2d covariance = Eigen::Matrix2d::Constant(std::numeric_limits<double>::quiet_NaN());
  bool ok = false;  // false: mass below DBL_MIN, Σ (numerically) singular or an input not finite
};

// log P(X > h, Y > k), X, Y standard normal with correlation rho, |rho| < 1; h, k may be −∞ (no bound)
// or +∞ (empty: returns −∞). NaN for NaN input or |rho| ≥ 1.
double LogUpperOrthantProbability(double h, double k, double rho);
// The same by adaptive quadrature only (the tail branch of LogUpperOrthantProbability; the reference of
// its closed form in the tests).
double LogUpperOrthantProbabilityByQuadrature(double h, double k, double rho);

// N(mean, covariance) restricted to {sides(i) · (s_i − bounds(i)) > 0}; sides(i) ∈ {−1, +1}. A bound of
// −∞·sides(i) leaves that coordinate unbounded. Never throws; ok = false on invalid input (non-finite
// mean/covariance, sides not ±1, correlation |ρ| ≥ 1 − 1e-12, non-positive variance) or a mass below
// the smallest normal double (log P < −708: the reading is impossible to double precision).
TruncatedBivariateMoments TruncatedBivariateNormalMoments(const Eigen::Vector2d& mean,
                                                          const Eigen::Matrix2d& covariance,
                                                          const Eigen::Vector2d& bounds, const Eigen::Vector2d& sides);

}  // namespace ident::models
