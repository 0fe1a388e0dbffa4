#include "models/noise_density.h"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <limits>
#include <numbers>

#include <boost/math/quadrature/gauss.hpp>
#include <boost/math/special_functions/erf.hpp>
#include <boost/math/special_functions/gamma.hpp>
#include <fmt/format.h>

#include "common/error.h"

namespace ident::models {
namespace {

constexpr double kNoiseNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kDefaultHuberK = 1.345;
const double kNoiseLogSqrt2Pi = 0.5 * std::log(2.0 * std::numbers::pi);

// ρ(u) = −log f(u) − log_norm for each family (the unnormalised negative log-density).
double Rho(LogConcaveNoise::Family family, double shape, double u) {
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
      return std::pow(au, shape);
  }
  return kNoiseNaN;
}

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

// exp(c·r)·N(r; a, v) on [lo, hi] = exp(c·a + c²v/2)·N(r; a + c·v, v) on [lo, hi]: one piece (c = ±k for the
// exponential tails of laplace and huber).
bool ExponentialPiece(double c, double a, double v, double lo, double hi, double log_c0, Piece& out) {
  const TiltedMoments t = TruncatedNormalMoments(a + c * v, v, lo, hi);
  if (!t.ok) return false;
  out = {log_c0 + c * a + 0.5 * c * c * v + t.log_normalizer, t.mean, t.variance};
  return true;
}

// g(y, s) = f(y − s) as a projected measurement on a scalar state (the quadrature reference).
class ResidualMeasurement final : public ProjectedMeasurement {
 public:
  explicit ResidualMeasurement(const LogConcaveNoise& noise) : ProjectedMeasurement(Eigen::VectorXd::Ones(1)), noise_(noise) {}
  std::string name() const override { return noise_.ToString(); }
  double LogLikelihoodScalar(double y, double s) const override { return noise_.LogDensity(y - s); }
  double ScalarStrength(double) const override { return 0.0; }
  bool IsValidOutput(double y) const override { return std::isfinite(y); }

 protected:
  Pieces SupportPieces(double y) const override {
    Pieces p;
    using F = LogConcaveNoise::Family;
    if (noise_.family() == F::kLaplace || noise_.family() == F::kGeneralizedGaussian) p.kinks[0] = y;
    if (noise_.family() == F::kHuber) {
      p.kinks[0] = y - noise_.shape();
      p.kinks[1] = y + noise_.shape();
    }
    return p;
  }

 private:
  const LogConcaveNoise& noise_;
};

// The median m of |u| under the density ∝ e^{−ρ(u)} (symmetric): P(|u| ≤ m) = 1/2, by bisection on a
// Gauss–Legendre integral of the unnormalised density (construction only).
double MedianAbsByQuadrature(LogConcaveNoise::Family family, double shape, double total_half) {
  using Gauss = boost::math::quadrature::gauss<double, 30>;
  auto integral = [&](double lo, double hi) {  // panels of width ≤ 0.25
    double sum = 0;
    const int panels = std::max(1, static_cast<int>(std::ceil((hi - lo) / 0.25)));
    for (int i = 0; i < panels; ++i)
      sum += Gauss::integrate([&](double u) { return std::exp(-Rho(family, shape, u)); },
                              lo + (hi - lo) * i / panels, lo + (hi - lo) * (i + 1) / panels);
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
      log_norm_ = std::log(2.0) + std::lgamma(1 / p) - std::log(p);
      median_abs_ = std::pow(boost::math::gamma_p_inv(1 / p, 0.5), 1 / p);
      sd_ = std::exp(0.5 * (std::lgamma(3 / p) - std::lgamma(1 / p)));
      break;
    }
  }
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
  throw InvalidArgument(fmt::format(
      "unknown noise '{}' (known: gaussian, laplace, huber[:k], logistic, gengauss:p)", spec));
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
      return s * shape_ * std::pow(au, shape_ - 1);
  }
  return kNoiseNaN;
}

double LogConcaveNoise::Weight(double u) const {
  const double au = std::abs(u);
  if (!(au > median_abs_)) return std::isnan(u) ? kNoiseNaN : 1.0;
  const double typical = Score(median_abs_) / median_abs_;
  return std::min(1.0, Score(au) / au / typical);
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
      // (laplace: k = 0, no middle piece, and no k²/2).
      const double k = family_ == Family::kHuber ? shape_ : 1.0;
      const double lo = family_ == Family::kHuber ? -k : 0.0, hi = -lo;
      const double offset = (family_ == Family::kHuber ? 0.5 * k * k : 0.0) - log_norm_;
      constexpr double kInfinity = std::numeric_limits<double>::infinity();
      std::array<Piece, 3> pieces{};
      int n = 0;
      if (ExponentialPiece(k, a, v, -kInfinity, lo, offset, pieces[n])) ++n;
      if (ExponentialPiece(-k, a, v, hi, kInfinity, offset, pieces[n])) ++n;
      if (family_ == Family::kHuber) {
        // e^{−r²/2}·N(r; a, v) = √(2π)·N(a; 0, 1 + v)·N(r; a/(1+v), v/(1+v)).
        const double s = 1 + v;
        const TiltedMoments t = TruncatedNormalMoments(a / s, v / s, lo, hi);
        if (t.ok)
          pieces[n++] = {-log_norm_ - 0.5 * a * a / s - 0.5 * std::log(s) + t.log_normalizer, t.mean, t.variance};
      }
      if (n == 0) return {};
      return Mix(pieces, n);
    }
    case Family::kLogistic:
    case Family::kGeneralizedGaussian:
      return RuleMoments(a, v);
  }
  return {};
}

TiltedMoments LogConcaveNoise::RuleMoments(double a, double v) const noexcept {
  // log h(r) = −ρ(r) − (r − a)²/(2v); h' = 0 at the mode, in [min(0, a), max(0, a)] since ψ(0) = 0 and ψ
  // has the sign of r. Safeguarded Newton on the decreasing −ψ(r) − (r − a)/v.
  const bool logistic = family_ == Family::kLogistic;
  // ρ'' (logistic: (1 − tanh²(r/2))/2 ≤ 1/4; gengauss: p(p − 1)|r|^(p−2), evaluated at |r| ≥ 1/2 so
  // that the kink of |r|^p at 0 does not shrink the width to nothing).
  auto curvature = [&](double r) {
    if (logistic) {
      const double t = std::tanh(0.5 * r);
      return 0.5 * (1 - t * t);
    }
    return shape_ * (shape_ - 1) * std::pow(std::max(std::abs(r), 0.5), shape_ - 2);
  };
  double lo = std::min(0.0, a), hi = std::max(0.0, a), r = std::clamp(a / (1 + 0.25 * v), lo, hi);
  for (int i = 0; i < 200; ++i) {
    const double g = -Score(r) - (r - a) / v;  // decreasing in r
    if (g > 0) lo = r; else hi = r;
    double next = r + g / (curvature(r) + 1 / v);
    if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
    const bool done = std::abs(next - r) <= 1e-14 * (1 + std::abs(r)) || hi - lo <= 1e-15 * (1 + std::abs(r));
    r = next;
    if (done) break;
  }
  const double width = 1 / std::sqrt(curvature(r) + 1 / v);
  const double log_peak = -Rho(family_, shape_, r) - 0.5 * (r - a) * (r - a) / v;
  // log h is concave with curvature ≤ −1/v and, for these families, tails no lighter than e^{−|r|}'s
  // beyond the width; ±16 widths in 12 panels of 10 Gauss–Legendre points leave below 1e−13 of the
  // mass. gengauss: a panel boundary at r = 0, where |r|^p is not smooth.
  using Gauss = boost::math::quadrature::gauss<double, 10>;
  const auto& x = Gauss::abscissa();
  const auto& w = Gauss::weights();
  constexpr int kPanels = 12;
  const double half = 16 * width, panel = 2 * half / kPanels;
  std::array<double, kPanels + 12> cuts{};
  int n = 0;
  for (int p = 0; p <= kPanels; ++p) cuts[n++] = r - half + p * panel;
  if (!logistic && cuts[0] < 0 && cuts[kPanels] > 0) {
    // |r|^p at 0: a boundary there and panels graded geometrically towards it (exponential convergence
    // for the r^p singularity instead of GL's algebraic one).
    cuts[n++] = 0;
    for (double g = 0.25; g > 1e-3; g *= 0.25)
      for (double c : {-g * panel, g * panel})
        if (c > cuts[0] && c < cuts[kPanels]) cuts[n++] = c;
    std::sort(cuts.begin(), cuts.begin() + n);
  }
  double z = 0, m1 = 0, m2 = 0;
  for (int p = 0; p + 1 < n; ++p) {
    const double centre = 0.5 * (cuts[p] + cuts[p + 1]), scale = 0.5 * (cuts[p + 1] - cuts[p]);
    for (std::size_t i = 0; i < x.size(); ++i) {
      for (int side : {1, -1}) {
        if (side < 0 && x[i] == 0) continue;
        const double rr = centre + side * scale * x[i], d = rr - r;
        const double h = scale * w[i] * std::exp(-Rho(family_, shape_, rr) - 0.5 * (rr - a) * (rr - a) / v - log_peak);
        z += h;
        m1 += h * d;
        m2 += h * d * d;
      }
    }
  }
  if (!(z > 0) || !std::isfinite(z)) return {};
  const double mean_d = m1 / z;
  const double var = std::max(0.0, m2 / z - mean_d * mean_d);
  // Z = ∫ f(r)·N(r; a, v) dr = e^{log_peak − log_norm}·z/√(2πv).
  return {log_peak - log_norm_ + std::log(z) - 0.5 * std::log(2 * std::numbers::pi * v), r + mean_d, var, true};
}

TiltedMoments LogConcaveNoise::QuadratureResidualMoments(double a, double v) const {
  // r = y − s with y = 0: r ~ N(a, v) ⇔ s ~ N(−a, v); the moments of r are those of −s.
  const ResidualMeasurement measurement(*this);
  const TiltedMoments t = measurement.QuadratureTilt(0.0, -a, v);
  if (!t.ok) return t;
  return {t.log_normalizer, -t.mean, t.variance, true};
}

}  // namespace ident::models
