// Delete-one-group jackknife standard error of a ratio of sums, R = Σ_b a_b / Σ_b c_b, over B groups
// (Efron & Tibshirani, "An Introduction to the Bootstrap", 1993, §11.2 and §11.5):
//   R_(b) = (Σ a − a_b) / (Σ c − c_b),   se² = (B−1)/B · Σ_b (R_(b) − mean_b R_(b))².
// Used for the MEMS study's calibration (mean predicted variance / mean squared error), whose groups are
// contiguous blocks of one run: serially correlated errors stay inside a block, so the blocks are close to
// independent when each spans several events.
//
// Preconditions: a.size() == c.size() >= 2 and Σ c − c_b ≠ 0 for every b (else the result is not finite).
//
// Example:
//   std::array<double, 10> var{...}, err2{...};                 // per-block sums
//   double se = ident::JackknifeRatioStandardError(var, err2);  // of Σ var / Σ err2
#pragma once

#include <cmath>
#include <cstddef>
#include <numeric>
#include <span>

namespace ident {

inline double JackknifeRatioStandardError(std::span<const double> a, std::span<const double> c) {
  const std::size_t groups = a.size();
  const double sum_a = std::accumulate(a.begin(), a.end(), 0.0);
  const double sum_c = std::accumulate(c.begin(), c.end(), 0.0);
  double mean = 0;
  for (std::size_t b = 0; b < groups; ++b) mean += (sum_a - a[b]) / (sum_c - c[b]);
  mean /= static_cast<double>(groups);
  double ss = 0;
  for (std::size_t b = 0; b < groups; ++b) {
    const double d = (sum_a - a[b]) / (sum_c - c[b]) - mean;
    ss += d * d;
  }
  return std::sqrt((static_cast<double>(groups) - 1) / static_cast<double>(groups) * ss);
}

}  // namespace ident
