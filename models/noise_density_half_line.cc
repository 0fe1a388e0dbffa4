// The gengauss moments of LogConcaveNoise (models/noise_density.h) for a prior narrow against f's scale with
// the kink of |r|^p at 0 inside it: Gauss rules on each half-line (models/internal/half_line_rules.h).
#include <cmath>
#include <numbers>

#include <Eigen/Core>

#include "models/internal/half_line_rules.h"
#include "models/internal/noise_density_shared.h"
#include "models/noise_density.h"

namespace ident::models {

namespace {

// Σ_i w_i·e^{δt_i + c − σ^p t_i^p}·(1, t_i, t_i²): one half-line's ∫ e^{−(t − α)²/2} e^{−(σt)^p} t^k dt, k = 0, 1, 2.
struct HalfLineSums {
  double z = 0, m1 = 0, m2 = 0;
};

template <int N>
HalfLineSums SumHalfLine(double alpha, double sd_p, double p) {
  using Array = Eigen::Array<double, N, 1>;
  const internal::HalfLineRule<N>& rule = internal::HalfLineRules<N>::Get().Nearest(alpha);
  const double delta = alpha - rule.alpha, c = -0.5 * delta * (alpha + rule.alpha);
  Array t_p;
  if (p == 1.5)
    t_p = rule.t * rule.s;
  else if (p == 1)
    t_p = rule.t;
  else
    t_p = (p * rule.log_t).exp();
  const Array h = rule.w * (delta * rule.t + c - sd_p * t_p).exp();
  return {h.sum(), (h * rule.t).sum(), (h * rule.t.square()).sum()};
}

template <int N>
TiltedMoments HalfLineMomentsOf(double a, double v, double p, double log_norm) {
  // t = r/√v: r ~ N(a, v) is t ~ N(α, 1), α = a/√v, and f(r) ∝ e^{−(√v·|t|)^p}; the half r < 0 is t' = −t ≥ 0
  // with α' = −α. The half away from α is skipped when its mass, at most √(2π)Φ(−|α|) < e^{−α²/2}/|α|
  // (Mills), is below 1e−17 of the other's.
  const double sd = std::sqrt(v), alpha = a / sd, sd_p = internal::GengaussPower(sd, p);
  const double near_sign = alpha >= 0 ? 1.0 : -1.0;
  const HalfLineSums near = SumHalfLine<N>(near_sign * alpha, sd_p, p);
  HalfLineSums far;
  const double abs_alpha = std::abs(alpha);
  if (!(abs_alpha > 6 && std::exp(-0.5 * abs_alpha * abs_alpha) / abs_alpha < 1e-17 * near.z))
    far = SumHalfLine<N>(-near_sign * alpha, sd_p, p);
  const double z = near.z + far.z;
  if (!(z > 0) || !std::isfinite(z)) return {};
  const double mean_t = near_sign * (near.m1 - far.m1) / z;
  const double var_t = std::max(0.0, (near.m2 + far.m2) / z - mean_t * mean_t);
  // Z = ∫ f(r) N(r; a, v) dr = e^{−log_norm}·z/√(2π).
  return {std::log(z) - 0.5 * std::log(2 * std::numbers::pi) - log_norm, sd * mean_t, v * var_t, true};
}

}  // namespace

TiltedMoments LogConcaveNoise::HalfLineMoments(double a, double v) const noexcept {
  // The rules' error grows with the variation of e^{−σ^p s^{2p}} across the weight. Where s^{2p} is a
  // polynomial (p = 1, 1.5; p = 2 has a closed form) 10 points reach 1e−11 up to √v = 0.15, 12 up to 0.25,
  // 16 up to 0.5 and 20 up to 0.75; for other p, 20 points reach 1e−10 up to √v = 0.4, 28 up to 0.5 and 40
  // up to 0.75 (tests/models/noise_density_test.cc).
  if (shape_ == 1 || shape_ == 1.5) {
    if (v <= 0.0225) return HalfLineMomentsOf<10>(a, v, shape_, log_norm_);
    if (v <= 0.0625) return HalfLineMomentsOf<12>(a, v, shape_, log_norm_);
    if (v <= 0.25) return HalfLineMomentsOf<16>(a, v, shape_, log_norm_);
    return HalfLineMomentsOf<20>(a, v, shape_, log_norm_);
  }
  if (v <= 0.16) return HalfLineMomentsOf<20>(a, v, shape_, log_norm_);
  if (v <= 0.25) return HalfLineMomentsOf<28>(a, v, shape_, log_norm_);
  return HalfLineMomentsOf<40>(a, v, shape_, log_norm_);
}

}  // namespace ident::models
