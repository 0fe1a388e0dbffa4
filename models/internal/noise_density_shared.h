// What the closed forms (noise_density.cc) and the quadratures (noise_density_quadrature.cc) of the log-concave
// noise families (models/noise_density.h) share: the unnormalised negative log-density ρ, and the
// Gauss–Hermite rules built at construction.
#pragma once

#include <cmath>
#include <limits>

#include "models/noise_density.h"

namespace ident::models::internal {

// |r|^p for the generalised Gaussian, r ≥ 0: the shapes 1, 1.5 and 2 without std::pow.
inline double GengaussPower(double r, double p) {
  if (p == 1.5) return r * std::sqrt(r);
  if (p == 2) return r * r;
  if (p == 1) return r;
  return std::pow(r, p);
}

// ρ(u) = −log f(u) − log_norm for each family (the unnormalised negative log-density).
inline double Rho(LogConcaveNoise::Family family, double shape, double u) {
  using F = LogConcaveNoise::Family;
  const double au = std::abs(u);
  switch (family) {
    case F::kGaussian:
      return 0.5 * u * u;
    case F::kLaplace:
      return au;
    case F::kHuber:
      return au <= shape ? 0.5 * u * u : shape * au - 0.5 * shape * shape;
    case F::kLogistic:
      return au + 2 * std::log1p(std::exp(-au));
    case F::kGeneralizedGaussian:
      return GengaussPower(au, shape);
  }
  return std::numeric_limits<double>::quiet_NaN();
}

// Builds the Gauss–Hermite rules of HermiteMoments once (later calls return at once); a constructor calls it
// so that no update pays for the build.
void BuildHermiteRules();

}  // namespace ident::models::internal
