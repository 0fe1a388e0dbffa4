// Log-concave noise densities for regression, y = z'θ + σ·u with u of a standard log-concave density f
// (Henningsson & Åström 2006, sec. III: log-concave measurement noise; every family below is LC(0), the
// Gaussian LC(1)):
//
//   gaussian         f(u) = φ(u)                                             median |u| = 0.674 49
//   laplace          f(u) = ½ e^{−|u|}                                       median |u| = ln 2
//   huber:k          f(u) = e^{−ρ_k(u)}/c_k, ρ_k = u²/2 (|u| ≤ k), k|u| − k²/2   (k = 1.345 unless given)
//   logistic         f(u) = e^{−u}/(1 + e^{−u})²                             median |u| = ln 3
//   gengauss:p       f(u) = p/(2Γ(1/p)) e^{−|u|^p}, 1 ≤ p ≤ 2                (p = 1 laplace, p = 2 ∝ gaussian)
//
// ResidualMoments(a, v) gives log Z, mean and variance of the tilted density f(r)·N(r; a, v)/Z of the
// standardised residual r = (y − s)/σ when s = z'θ has the Gaussian prior N(μ, σ²v) and a = (y − μ)/σ: the
// one-dimensional part of the log-concave Gaussian filter's measurement update (ident/observers/lc_gaussian_filter.h),
// which is exact for a measurement that depends on θ only through s.
//   gaussian         closed form (a product of Gaussians)
//   laplace, huber   closed form: a mixture of two or three truncated normals (models/measurement.h
//                    TruncatedNormalMoments), combined in log space and centred
//   logistic         a prior small against f's scale (the steady state): 8- to 64-point Gauss–Hermite in the
//                    prior N(a, v), the rule chosen by v; otherwise composite 10-point Gauss–Legendre on panels
//                    of width ≤ 2 around the mode of the (log-concave, unimodal) tilted density, until it has
//                    fallen by e^{−45}, the mode by safeguarded Newton
//   gengauss         p = 2: closed form. Otherwise |u|^p is not smooth at 0. With 0 twelve prior widths away: Gauss–Hermite in the prior, or
//                    (f steep across the prior) centred on the mode with its curvature; with 0 inside a prior of
//                    √v ≤ 0.75: Gauss rules on each half-line in s = √|r| (models/internal/half_line_rules.h);
//                    else the Gauss–Legendre panels, with a boundary at 0 and panels graded towards it
//   The laplace and huber tails: Mills-ratio continued fractions beyond 25 standard deviations, erfc below;
//   a mixture piece whose weight bound is below e^{−80} of the largest is not evaluated.
//   All agree with adaptive quadrature to 1e−10 relative (tests/models/noise_density_test.cc).
// No allocation.
//
// Weight(u) is the sample's relative weight in M-estimation, ψ(u)/u against a typical residual:
// 1 for |u| ≤ median|u|, then min(1, [ψ(u)/u]/[ψ(m)/m]) (m = median|u|). The Gaussian weighs every sample
// alike (1); a Laplace residual of 5 MADs gets 0.2.
//
// Example:
//   auto noise = ident::models::LogConcaveNoise::Parse("huber:1.345");
//   ident::models::TiltedMoments t = noise.ResidualMoments(/*a=*/3.0, /*v=*/0.5);
#pragma once

#include <optional>
#include <string>
#include <string_view>

#include "models/measurement.h"

namespace ident::models {

class LogConcaveNoise {
 public:
  enum class Family { kGaussian, kLaplace, kHuber, kLogistic, kGeneralizedGaussian };

  // Throws InvalidArgument for k ≤ 0 (Huber), p < 1 or p > 2 (generalised Gaussian), non-finite shapes.
  explicit LogConcaveNoise(Family family, double shape = 0);
  // "gaussian", "laplace", "huber" (k = 1.345), "huber:K", "logistic", "gengauss:P". Throws InvalidArgument
  // naming the spec and the known families.
  static LogConcaveNoise Parse(std::string_view spec);

  Family family() const { return family_; }
  double shape() const { return shape_; }  // k (huber), p (gengauss), else 0
  std::string ToString() const;            // the spec Parse reads back ("huber:1.345")

  // log f(u), the standard density.
  double LogDensity(double u) const;
  // ψ(u) = −d/du log f(u) (the score; 0 at the kink of laplace).
  double Score(double u) const;
  double Weight(double u) const;
  // The median of |u| under f (consistency factor of the MAD: σ = MAD/median|u|).
  double median_abs() const { return median_abs_; }
  // The standard deviation of u under f (σ·it is the noise's).
  double standard_deviation() const { return sd_; }

  // Moments of f(r)·N(r; a, v)/Z, v > 0. ok = false if Z underflows or the arguments are not finite.
  TiltedMoments ResidualMoments(double a, double v) const noexcept;
  // The same by adaptive quadrature (the reference for the closed forms and the Gauss–Legendre rule).
  TiltedMoments QuadratureResidualMoments(double a, double v) const;

 private:
  // logistic and gengauss: Gauss–Legendre panels around the mode of the tilted density.
  TiltedMoments RuleMoments(double a, double v) const noexcept;
  // logistic and gengauss away from 0: a Gauss–Hermite rule (index into the rules) in the prior N(a, v).
  TiltedMoments HermiteMoments(double a, double v, int rule) const noexcept;
  // gengauss with the mode 12 widths (1/√(−(log h)'')) from 0: the 20-point Gauss–Hermite rule centred on the mode.
  TiltedMoments ModeHermiteMoments(double a, double v, double mode, double width, double log_peak) const noexcept;
  // gengauss, v ≤ internal::kHalfLineMaxVariance and |a| < 12√v: Gauss rules on each half-line in √|r|.
  TiltedMoments HalfLineMoments(double a, double v) const noexcept;

  Family family_;
  double shape_ = 0;
  double log_norm_ = 0;  // log of f's normalising constant (f = e^{−ρ(u)} / e^{log_norm_})
  double median_abs_ = 0;
  double sd_ = 1;
  double typical_ratio_ = 1;  // ψ(m)/m at m = median|u| (Weight)
};

}  // namespace ident::models
