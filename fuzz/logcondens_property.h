// Property of the log-concave MLE (approx::FitLogConcaveMle, behind `ident logcondens`) on arbitrary
// samples.
// Input: 1 mode byte, then samples (at most 256):
//   mode 0: raw doubles, any bit pattern (NaN, ±Inf, subnormals, ±1e308 all occur);
//   mode 1: a scale byte s, then one byte per sample: (byte − 128)·2^(s − 128) (ties, any scale);
//   mode 2: int16 per sample / 256 (moderate values, few ties).
// Holds if FitLogConcaveMle throws nothing but ident::InvalidArgument, and a returned estimate
// satisfies the characterisation of the MLE ([DHR] Theorem 2.4), checked by CheckKkt with tolerances
// scaled by the data range r = x_m − x_1: max_j D_j <= 1e-7·r, |D_j| <= 1e-7·r at the knots,
// |∫exp(φ) − 1| <= 1e-7, slope increases <= 1e-7 of the largest |slope| plus the rounding
// of φ over the two gaps; and φ, the log-likelihood
// and the knots (first x_1, last x_m, increasing) are finite.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "common/error.h"
#include "fuzz/fuzz_util.h"
#include "ident/density/logconcave_mle.h"

namespace ident::fuzz {

inline std::vector<double> LogcondensSamples(const std::uint8_t* data, std::size_t size) {
  ByteReader in(data, size);
  const int mode = in.Byte() % 3;
  std::vector<double> x;
  if (mode == 0) {
    while (in.remaining() >= 8 && x.size() < 256) x.push_back(in.Double());
  } else if (mode == 1) {
    const double scale = std::ldexp(1.0, static_cast<int>(in.Byte()) - 128);
    while (in.remaining() >= 1 && x.size() < 256) x.push_back((static_cast<int>(in.Byte()) - 128) * scale);
  } else {
    while (in.remaining() >= 2 && x.size() < 256) {
      const std::uint16_t lo = in.Byte(), hi = in.Byte();
      x.push_back(static_cast<std::int16_t>(lo | (hi << 8)) / 256.0);
    }
  }
  return x;
}

inline std::string LogcondensProperty(const std::uint8_t* data, std::size_t size) {
  const std::vector<double> samples = LogcondensSamples(data, size);
  approx::LogConcaveMle mle;
  try {
    mle = approx::FitLogConcaveMle(samples);
  } catch (const InvalidArgument&) {
    return {};  // the expected answer to unusable samples
  } catch (...) {
    return "FitLogConcaveMle throws only InvalidArgument";
  }
  const int m = static_cast<int>(mle.x.size());
  if (m < 2 || mle.phi.size() != m || mle.knots.size() < 2) return "at least 2 distinct values and 2 knots";
  if (!mle.phi.allFinite() || !std::isfinite(mle.loglik) || !mle.knots.allFinite()) return "phi, loglik, knots finite";
  if (mle.knots(0) != mle.x(0) || mle.knots(mle.knots.size() - 1) != mle.x(m - 1)) return "knots span [x_1, x_m]";
  for (int a = 1; a < mle.knots.size(); ++a)
    if (!(mle.knots(a) > mle.knots(a - 1))) return "knots increase";
  const double range = mle.x(m - 1) - mle.x(0);
  double max_slope = 0;
  for (int j = 0; j + 1 < m; ++j)
    max_slope = std::max(max_slope, std::abs((mle.phi(j + 1) - mle.phi(j)) / (mle.x(j + 1) - mle.x(j))));
  const approx::LogConcaveKkt kkt = approx::CheckKkt(mle);
  if (!(kkt.max_directional_derivative <= 1e-7 * range)) return "KKT: max D_j <= 0";
  if (!(kkt.max_knot_residual <= 1e-7 * range)) return "KKT: D_j = 0 at the knots";
  if (!(kkt.mass_error <= 1e-7)) return "KKT: the density integrates to 1";
  // Concave up to the rounding of the stored φ: a slope over a gap g carries an error of about
  // ε·|φ|/g, which dominates at tiny (e.g. subnormal) spacings; where φ is 0 (a uniform density) there is
  // none, also when 1/g overflows (0·∞ would be NaN).
  for (int j = 1; j + 1 < m; ++j) {
    const double gl = mle.x(j) - mle.x(j - 1), gr = mle.x(j + 1) - mle.x(j);
    const double left = (mle.phi(j) - mle.phi(j - 1)) / gl, right = (mle.phi(j + 1) - mle.phi(j)) / gr;
    const double size = std::max({std::abs(mle.phi(j - 1)), std::abs(mle.phi(j)), std::abs(mle.phi(j + 1))});
    const double rounding = size == 0 ? 0.0 : 8 * std::numeric_limits<double>::epsilon() * size * (1 / gl + 1 / gr);
    if (!(right - left <= 1e-7 * max_slope + rounding)) return "phi is concave";
  }
  return {};
}

}  // namespace ident::fuzz
