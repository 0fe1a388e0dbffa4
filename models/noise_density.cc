// LogConcaveNoise (models/noise_density.h): the families' constants, parsing, and the closed-form tilted
// moments (Gaussian; Laplace and Huber as mixtures of truncated normals) that choose the quadratures otherwise.
#include "models/noise_density.h"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <limits>
#include <numbers>

#include <fmt/format.h>
#include <boost/math/quadrature/gauss.hpp>
#include <boost/math/special_functions/erf.hpp>
#include <boost/math/special_functions/gamma.hpp>

#include "common/error.h"
#include "models/internal/half_line_rules.h"
#include "models/internal/noise_density_shared.h"

namespace ident::models {

using internal::Rho;

namespace {

constexpr double kNoiseNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kDefaultHuberK = 1.345;
const double kNoiseLogSqrt2Pi = 0.5 * std::log(2.0 * std::numbers::pi);
// A mixture piece whose log-weight bound is this far below the largest exact log-weight is left out: its
// share e^{−80} ≈ 2e−35 moves the mean and variance by less than 1e−16 of theirs for |a| up to 1e8.
constexpr double kNegligibleLogWeight = 80;

// One piece of a mixture: log of its weight (log C + log Z of its truncated normal) and its moments.
struct Piece {
  double log_weight;
  double mean;
  double variance;
};

// Mixture of the pieces with ok moments, combined in log space and centred (no cancellation in the
// variance when the mean is large).
template <std::size_t N>
TiltedMoments Mix(const std::array<Piece, N>& pieces, int count) {
  double top = -std::numeric_limits<double>::infinity();
  for (int i = 0; i < count; ++i) top = std::max(top, pieces[i].log_weight);
  if (!std::isfinite(top)) return {};
  double total = 0, mean = 0;
  std::array<double, N> w{};
  for (int i = 0; i < count; ++i) {
    w[i] = std::exp(pieces[i].log_weight - top);
    total += w[i];
  }
  for (int i = 0; i < count; ++i) mean += w[i] / total * pieces[i].mean;
  double var = 0;
  for (int i = 0; i < count; ++i) {
    const double d = pieces[i].mean - mean;
    var += w[i] / total * (pieces[i].variance + d * d);
  }
  return {top + std::log(total), mean, var, true};
}

// Moments of the standard normal restricted to [x, ∞): Z = Q(x), mean λ = φ(x)/Q(x), variance 1 − λ(λ − x).
// x < 25: Q from erfc, accurate to a few ulp relative down to its underflow near x = 37; the variance
// (≈ 1/x² far out) loses at most x²·ε ≤ 1.4e−13 of itself to cancellation. x ≥ 25: the continued fraction
// t_k = x + k/t_(k+1) of the Mills ratio, Q(x)/φ(x) = 1/t_1, mean = t_1 = x + 1/t_2 and variance
// (2/t_3 − 1/t_2)/t_2, free of cancellation; started at k = ⌈130/x⌉ + 5 terms (11 at x = 25, 8 at x = 50),
// which keeps t_1, the mean and the variance within 5e−16 relative for x in [5, 100] (checked against
// 40-digit erfc; the error falls with x). Its terms are a chain of divisions, so erfc is the cheaper below 25.
TiltedMoments UpperTailMoments(double x) noexcept {
  if (x < 25) {
    const double q = 0.5 * std::erfc(x * (0.5 * std::numbers::sqrt2));
    const double log_phi = -0.5 * x * x - kNoiseLogSqrt2Pi;
    const double lambda = std::exp(log_phi) / q;
    return {std::log(q), lambda, std::max(0.0, 1 - lambda * (lambda - x)), true};
  }
  const int terms = static_cast<int>(std::ceil(130 / x)) + 5;
  double t1 = x, t2 = x, t3 = x;
  for (int k = terms; k >= 1; --k) {
    t3 = t2;
    t2 = t1;
    t1 = x + k / t1;
  }
  return {-0.5 * x * x - kNoiseLogSqrt2Pi - std::log(t1), x + 1 / t2, (2 / t3 - 1 / t2) / t2, true};
}

// log Q(x) ≤ this (Q(x) ≤ ½e^{−x²/2} for x ≥ 0, Q ≤ 1): the cheap bound that skips negligible pieces.
double LogUpperTailBound(double x) { return x > 0 ? -0.5 * x * x - std::numbers::ln2 : 0.0; }

// Largest prior variance v (in units of σ²) for each Gauss–Hermite rule of kHermiteSizes
// (noise_density_quadrature.cc).
constexpr std::array<double, 9> kHermiteMaxVariance = {0.015, 0.06, 0.12, 0.2, 0.25, 0.4, 0.55, 0.8, 1.0};

// The median m of |u| under the density ∝ e^{−ρ(u)} (symmetric): P(|u| ≤ m) = 1/2, by bisection on a
// Gauss–Legendre integral of the unnormalised density (construction only).
double MedianAbsByQuadrature(LogConcaveNoise::Family family, double shape, double total_half) {
  using Gauss = boost::math::quadrature::gauss<double, 30>;
  auto integral = [&](double lo, double hi) {  // panels of width ≤ 0.25
    double sum = 0;
    const int panels = std::max(1, static_cast<int>(std::ceil((hi - lo) / 0.25)));
    for (int i = 0; i < panels; ++i)
      sum += Gauss::integrate([&](double u) { return std::exp(-Rho(family, shape, u)); }, lo + (hi - lo) * i / panels,
                              lo + (hi - lo) * (i + 1) / panels);
    return sum;
  };
  // ∫_0^m e^{−ρ}, split at the Huber corner, where ρ has a kink.
  const double corner = family == LogConcaveNoise::Family::kHuber ? shape : std::numeric_limits<double>::infinity();
  auto mass = [&](double m) { return m <= corner ? integral(0, m) : integral(0, corner) + integral(corner, m); };
  double lo = 0, hi = 1;
  while (mass(hi) < 0.5 * total_half) hi *= 2;
  for (int i = 0; i < 200 && hi - lo > 1e-15 * hi; ++i) {
    const double mid = 0.5 * (lo + hi);
    (mass(mid) < 0.5 * total_half ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

}  // namespace

LogConcaveNoise::LogConcaveNoise(Family family, double shape) : family_(family), shape_(shape) {
  switch (family) {
    case Family::kGaussian:
      shape_ = 0;
      log_norm_ = kNoiseLogSqrt2Pi;
      median_abs_ = boost::math::erf_inv(0.5) * std::numbers::sqrt2;
      break;
    case Family::kLaplace:
      shape_ = 0;
      log_norm_ = std::log(2.0);
      median_abs_ = std::log(2.0);
      sd_ = std::numbers::sqrt2;
      break;
    case Family::kHuber: {
      IDENT_REQUIRE(std::isfinite(shape) && shape > 0, "Huber noise: k = {}; need a finite k > 0", shape);
      const double k = shape;
      // ∫ e^{−ρ_k} = √(2π)(2Φ(k) − 1) + 2 e^{−k²/2}/k.
      const double half = std::sqrt(2 * std::numbers::pi) * 0.5 * boost::math::erf(k / std::numbers::sqrt2) +
                          std::exp(-0.5 * k * k) / k;
      log_norm_ = std::log(2 * half);
      median_abs_ = MedianAbsByQuadrature(family, k, half);
      // E u² = [√(2π)(2Φ(k) − 1) + e^{−k²/2}(4/k + 4/k³)] / ∫ e^{−ρ_k}.
      sd_ = std::sqrt((std::sqrt(2 * std::numbers::pi) * boost::math::erf(k / std::numbers::sqrt2) +
                       std::exp(-0.5 * k * k) * (4 / k + 4 / (k * k * k))) /
                      (2 * half));
      break;
    }
    case Family::kLogistic:
      internal::BuildHermiteRules();  // built here, not in the first update
      shape_ = 0;
      log_norm_ = 0;  // e^{−u}/(1 + e^{−u})² integrates to 1
      median_abs_ = std::log(3.0);
      sd_ = std::numbers::pi / std::sqrt(3.0);
      break;
    case Family::kGeneralizedGaussian: {
      IDENT_REQUIRE(std::isfinite(shape) && shape >= 1 && shape <= 2,
                    "generalised Gaussian noise: p = {}; need 1 <= p <= 2 (log-concave, tails no lighter than "
                    "Gaussian)",
                    shape);
      const double p = shape;
      internal::BuildHermiteRules();
      // The half-line rules HalfLineMoments uses for this p (noise_density_half_line.cc; p = 2 has a closed form).
      if (p == 1 || p == 1.5) {
        internal::HalfLineRules<10>::Get();
        internal::HalfLineRules<12>::Get();
        internal::HalfLineRules<16>::Get();
        internal::HalfLineRules<20>::Get();
      } else if (p != 2) {
        internal::HalfLineRules<20>::Get();
        internal::HalfLineRules<28>::Get();
        internal::HalfLineRules<40>::Get();
      }
      log_norm_ = std::log(2.0) + std::lgamma(1 / p) - std::log(p);
      median_abs_ = std::pow(boost::math::gamma_p_inv(1 / p, 0.5), 1 / p);
      sd_ = std::exp(0.5 * (std::lgamma(3 / p) - std::lgamma(1 / p)));
      break;
    }
  }
  typical_ratio_ = Score(median_abs_) / median_abs_;
}

LogConcaveNoise LogConcaveNoise::Parse(std::string_view spec) {
  const auto colon = spec.find(':');
  const std::string_view name = spec.substr(0, colon);
  std::optional<double> shape;
  if (colon != std::string_view::npos) {
    const std::string_view arg = spec.substr(colon + 1);
    double value = 0;
    const auto [ptr, ec] = std::from_chars(arg.data(), arg.data() + arg.size(), value);
    IDENT_REQUIRE(!arg.empty() && ec == std::errc() && ptr == arg.data() + arg.size(),
                  "noise '{}': '{}' is not a number (use e.g. huber:1.345 or gengauss:1.5)", spec, arg);
    shape = value;
  }
  auto no_shape = [&](Family f) {
    IDENT_REQUIRE(!shape, "noise '{}': {} takes no parameter", spec, name);
    return LogConcaveNoise(f);
  };
  if (name == "gaussian") return no_shape(Family::kGaussian);
  if (name == "laplace") return no_shape(Family::kLaplace);
  if (name == "logistic") return no_shape(Family::kLogistic);
  if (name == "huber") return LogConcaveNoise(Family::kHuber, shape.value_or(kDefaultHuberK));
  if (name == "gengauss") {
    IDENT_REQUIRE(shape.has_value(), "noise '{}': gengauss needs its exponent p >= 1 (e.g. gengauss:1.5)", spec);
    return LogConcaveNoise(Family::kGeneralizedGaussian, *shape);
  }
  throw InvalidArgument(
      fmt::format("unknown noise '{}' (known: gaussian, laplace, huber[:k], logistic, gengauss:p)", spec));
}

std::string LogConcaveNoise::ToString() const {
  switch (family_) {
    case Family::kGaussian:
      return "gaussian";
    case Family::kLaplace:
      return "laplace";
    case Family::kHuber:
      return fmt::format("huber:{}", shape_);
    case Family::kLogistic:
      return "logistic";
    case Family::kGeneralizedGaussian:
      return fmt::format("gengauss:{}", shape_);
  }
  return "";
}

double LogConcaveNoise::LogDensity(double u) const { return -Rho(family_, shape_, u) - log_norm_; }

double LogConcaveNoise::Score(double u) const {
  const double s = u > 0 ? 1.0 : (u < 0 ? -1.0 : 0.0), au = std::abs(u);
  switch (family_) {
    case Family::kGaussian:
      return u;
    case Family::kLaplace:
      return s;
    case Family::kHuber:
      return std::clamp(u, -shape_, shape_);
    case Family::kLogistic:
      return std::tanh(0.5 * u);
    case Family::kGeneralizedGaussian:
      return s * shape_ * (shape_ == 1.5 ? std::sqrt(au) : shape_ == 2 ? au : std::pow(au, shape_ - 1));
  }
  return kNoiseNaN;
}

double LogConcaveNoise::Weight(double u) const {
  const double au = std::abs(u);
  if (!(au > median_abs_)) return std::isnan(u) ? kNoiseNaN : 1.0;
  return std::min(1.0, Score(au) / au / typical_ratio_);
}

TiltedMoments LogConcaveNoise::ResidualMoments(double a, double v) const noexcept {
  if (!(std::isfinite(a) && v > 0 && std::isfinite(v))) return {};
  switch (family_) {
    case Family::kGaussian: {
      // φ(r)·N(r; a, v) = N(a; 0, 1 + v)·N(r; a/(1 + v), v/(1 + v)).
      const double s = 1 + v;
      return {-0.5 * a * a / s - 0.5 * std::log(s) - kNoiseLogSqrt2Pi, a / s, v / s, true};
    }
    case Family::kLaplace:
    case Family::kHuber: {
      // f(r) = e^{−ρ(r)}/e^{log_norm}: e^{k r + k²/2} below −k, e^{−r²/2} on [−k, k], e^{−k r + k²/2} above k
      // (laplace: k = 1, no middle piece, the tails meet at 0 and no k²/2). A tail piece is
      // e^{±k r}·N(r; a, v) = e^{±k a + k²v/2}·N(r; a ± k v, v), a normal on a half-line: its standardised
      // bound x gives Z = Q(x) (UpperTailMoments; the lower tail mirrored). Pieces whose weight bound is
      // negligible against the largest exact weight are not evaluated (an outlier has one piece).
      const bool huber = family_ == Family::kHuber;
      const double k = huber ? shape_ : 1.0, corner = huber ? shape_ : 0.0, sd = std::sqrt(v);
      const double offset = (huber ? 0.5 * k * k : 0.0) - log_norm_;
      const double x_lo = (corner + a + k * v) / sd, x_hi = (corner - a + k * v) / sd;  // r ≤ −corner, r ≥ corner
      const double c_lo = offset + k * a + 0.5 * k * k * v, c_hi = offset - k * a + 0.5 * k * k * v;
      // Middle (huber): e^{−r²/2}·N(r; a, v) = √(2π)·N(a; 0, 1 + v)·N(r; a/(1+v), v/(1+v)) on [−k, k].
      const double s = 1 + v, m_mid = a / s, sd_mid = std::sqrt(v / s);
      const double c_mid = -log_norm_ - 0.5 * a * a / s - 0.5 * std::log(s);
      const double l_mid = (-corner - m_mid) / sd_mid, u_mid = (corner - m_mid) / sd_mid;
      std::array<double, 3> bound = {c_lo + LogUpperTailBound(x_lo), c_hi + LogUpperTailBound(x_hi),
                                     huber ? c_mid + (l_mid > 0 ? LogUpperTailBound(l_mid) : LogUpperTailBound(-u_mid))
                                           : -std::numeric_limits<double>::infinity()};
      std::array<int, 3> order = {0, 1, 2};
      std::sort(order.begin(), order.end(), [&](int i, int j) { return bound[i] > bound[j]; });
      std::array<Piece, 3> pieces{};
      int n = 0;
      double top = -std::numeric_limits<double>::infinity();
      for (int i : order) {
        if (!(bound[i] >= top - kNegligibleLogWeight)) continue;
        if (i == 0) {  // −r ~ N(−(a + k v), v) on [corner, ∞)
          const TiltedMoments t = UpperTailMoments(x_lo);
          pieces[n] = {c_lo + t.log_normalizer, a + k * v - sd * t.mean, v * t.variance};
        } else if (i == 1) {
          const TiltedMoments t = UpperTailMoments(x_hi);
          pieces[n] = {c_hi + t.log_normalizer, a - k * v + sd * t.mean, v * t.variance};
        } else {
          const TiltedMoments t = TruncatedNormalMoments(m_mid, v / s, -corner, corner);
          if (!t.ok) continue;
          pieces[n] = {c_mid + t.log_normalizer, t.mean, t.variance};
        }
        if (!std::isfinite(pieces[n].log_weight)) continue;
        top = std::max(top, pieces[n].log_weight);
        ++n;
      }
      if (n == 0) return {};
      return Mix(pieces, n);
    }
    case Family::kLogistic:
    case Family::kGeneralizedGaussian: {
      // Gauss–Hermite in the prior N(a, v) while f is smooth and slowly varying across it; else the rule.
      // logistic: f is analytic in the strip |Im r| < π, so the n-point rule converges geometrically in
      // π/√v; the largest v per rule keeps the error below 1e−13 (checked against 30-digit quadrature
      // on a grid of a; the unit test holds it to 1e−10 against adaptive quadrature). gengauss: |r|^p is
      // not smooth at 0, so 0 must lie 12 prior widths away, and f's slope ψ(a) stretches v to v·ψ(a)².
      double v_eff = v;
      if (family_ == Family::kGeneralizedGaussian && shape_ == 2) {
        // e^{−r²}/√π = N(r; 0, ½): φ-products in closed form, N(r; 0, ½)·N(r; a, v) = N(a; 0, ½ + v)·N(r; a/(1 + 2v),
        // v/(1 + 2v)).
        const double s = 0.5 + v;
        return {-0.5 * a * a / s - 0.5 * std::log(s) - kNoiseLogSqrt2Pi, 0.5 * a / s, 0.5 * v / s, true};
      }
      if (family_ == Family::kGeneralizedGaussian) {
        if (!(std::abs(a) >= 12 * std::sqrt(v)))
          return v <= internal::kHalfLineMaxVariance ? HalfLineMoments(a, v) : RuleMoments(a, v);
        v_eff = v * std::max(1.0, Score(a) * Score(a));
      }
      for (std::size_t r = 0; r < kHermiteMaxVariance.size(); ++r)
        if (v_eff <= kHermiteMaxVariance[r]) return HermiteMoments(a, v, static_cast<int>(r));
      return RuleMoments(a, v);
    }
  }
  return {};
}

}  // namespace ident::models
