// Helpers of the weighting-polynomial tests: the cubic P(β) = μ0 + μ1 β + μ2 β² + μ3 β³ by Horner, and
// the sum of the absolute values of its terms (the scale of P's rounding error at β).
#pragma once

#include <array>
#include <cmath>

namespace ident::approx::testing {

inline double EvalP(const std::array<double, 4>& mu, double b) { return ((mu[3] * b + mu[2]) * b + mu[1]) * b + mu[0]; }
inline double AbsTerms(const std::array<double, 4>& mu, double b) {
  return std::abs(mu[0]) + std::abs(mu[1] * b) + std::abs(mu[2] * b * b) + std::abs(mu[3] * b * b * b);
}

}  // namespace ident::approx::testing
