#include "models/measurement.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include <boost/math/quadrature/gauss.hpp>
#include <boost/math/quadrature/gauss_kronrod.hpp>

#include "common/error.h"

namespace ident::models {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
const double kLogSqrt2Pi = 0.5 * std::log(2.0 * std::numbers::pi);

double LogPhi(double x) { return std::isinf(x) ? -kInf : -0.5 * x * x - kLogSqrt2Pi; }  // log φ(x)

void RequireDirection(const Eigen::VectorXd& c) {
  IDENT_REQUIRE(c.size() >= 1 && c.allFinite() && c.squaredNorm() > 0,
                "measurement direction c must be a finite non-zero vector (size {})", c.size());
}

// Moments of the standard normal restricted to [a, b] with 0 ≤ a, b − a ≤ 1 (narrow, one tail):
// 40-point Gauss–Legendre on exp(−(s² − a²)/2), smooth on a short interval, so exact to rounding.
TiltedMoments NarrowStandardMoments(double a, double b) {
  using Gauss = boost::math::quadrature::gauss<double, 40>;
  auto w = [a](double s) { return std::exp(-0.5 * (s - a) * (s + a)); };
  const double z = Gauss::integrate(w, a, b);
  const double mean = Gauss::integrate([&](double s) { return s * w(s); }, a, b) / z;
  const double var = Gauss::integrate([&](double s) { return (s - mean) * (s - mean) * w(s); }, a, b) / z;
  return {std::log(z) + LogPhi(a), mean, var, true};
}

// The result if it is a valid set of moments (finite log Z and mean, 0 ≤ variance < ∞), else {}
// (ok = false): Z underflowed or rounding broke a moment.
TiltedMoments Checked(const TiltedMoments& t) {
  if (!t.ok || !std::isfinite(t.log_normalizer) || !std::isfinite(t.mean) || !(t.variance >= 0) ||
      !std::isfinite(t.variance)) {
    return {};
  }
  return t;
}

// Standard normal restricted to [a, b] with b > 0 and a < b (a may be −∞, b may be +∞).
TiltedMoments UpperStandardTruncatedMoments(double a, double b) {
  double log_z;
  if (a >= 10 && (b - a) * a > 40) {
    // Far upper tail, effectively a half-line (the mass beyond b is below e^(−40) of Z): moments from the
    // continued fraction t_k = a + k / t_(k+1) of the Mills ratio, Q(a)/φ(a) = 1/t_1. Then
    // mean = t_1 = a + 1/t_2 and var = 1 − t_1 (t_1 − a) = (2/t_3 − 1/t_2)/t_2, free of cancellation.
    double t1 = a, t2 = a, t3 = a;
    for (int k = 120; k >= 1; --k) {
      t3 = t2;
      t2 = t1;
      t1 = a + k / t1;
    }
    // After the loop: t1 = t_1, t2 = t_2, t3 = t_3.
    return {LogPhi(a) - std::log(t1), a + 1 / t2, (2 / t3 - 1 / t2) / t2, true};
  }
  if (a >= 0) {
    if (b - a <= 1.0) return NarrowStandardMoments(a, b);
    const double la = LogNormalTail(a), lb = LogNormalTail(b);  // Z = Q(a) − Q(b), both in the upper tail
    log_z = la + std::log1p(-std::exp(lb - la));
  } else {  // a < 0 < b: Z = ½ erf(b/√2) + ½ erf(−a/√2), a sum of positive terms
    // erf(x) rounds to 1 for x >= 5.93 (1 − erf(5.93) = 5.0e−17 < ε/2): a bound that far out costs no call.
    const double r = std::numbers::sqrt2 / 2;
    auto erf_to = [r](double bound) { return bound * r >= 5.93 ? 1.0 : std::erf(bound * r); };
    const double z = 0.5 * erf_to(b) + 0.5 * erf_to(-a);
    if (b - a <= 1.0) {  // narrow interval around 0: quadrature avoids cancellation in the variance
      using Gauss = boost::math::quadrature::gauss<double, 40>;
      auto w = [](double s) { return std::exp(-0.5 * s * s); };
      const double z0 = Gauss::integrate(w, a, b);
      const double mean = Gauss::integrate([&](double s) { return s * w(s); }, a, b) / z0;
      const double var = Gauss::integrate([&](double s) { return (s - mean) * (s - mean) * w(s); }, a, b) / z0;
      return {std::log(z), mean, var, true};
    }
    log_z = std::log(z);
  }
  if (!std::isfinite(log_z)) return {};
  const double ra = std::exp(LogPhi(a) - log_z), rb = std::exp(LogPhi(b) - log_z);  // φ(a)/Z, φ(b)/Z
  const double a_ra = std::isinf(a) ? 0.0 : a * ra, b_rb = std::isinf(b) ? 0.0 : b * rb;
  const double mean = ra - rb;
  const double var = std::max(0.0, 1.0 + a_ra - b_rb - mean * mean);
  return {log_z, mean, var, true};
}

}  // namespace

double LogNormalDensity(double x) { return LogPhi(x); }

double LogNormalTail(double x) {
  if (x < 30.0) return std::log(0.5 * std::erfc(x * std::numbers::sqrt2 / 2));
  // Mills ratio Q(x)/φ(x) = 1/(x + 1/(x + 2/(x + 3/(x + ...)))), converged for x ≥ 30.
  double f = x;
  for (int k = 60; k >= 1; --k) f = x + k / f;
  return LogPhi(x) - std::log(f);
}

// No recursion: b ≤ 0 is reflected once onto (−b, −a), whose upper bound −a > −b ≥ 0 (the fuzz
// finding: reflecting a = b = 0 onto itself recursed for ever).
TiltedMoments StandardTruncatedMoments(double a, double b) {
  if (!(a < b)) return {};  // also NaN
  if (b > 0) return Checked(UpperStandardTruncatedMoments(a, b));
  TiltedMoments t = Checked(UpperStandardTruncatedMoments(-b, -a));  // the lower tail, mirrored
  t.mean = -t.mean;
  return t;
}

TiltedMoments TruncatedNormalMoments(double mean, double variance, double lo, double hi) {
  IDENT_REQUIRE(variance > 0 && std::isfinite(variance) && std::isfinite(mean),
                "prior mean = {}, variance = {}; need finite mean and variance > 0", mean, variance);
  const double sd = std::sqrt(variance);
  // An empty or NaN interval gives a < b false after standardising, hence ok = false (no mass).
  const TiltedMoments t = StandardTruncatedMoments((lo - mean) / sd, (hi - mean) / sd);
  if (!t.ok) return {};
  return Checked({t.log_normalizer, mean + sd * t.mean, variance * t.variance, true});
}

// ---- ProjectedMeasurement -------------------------------------------------------------------------

ProjectedMeasurement::ProjectedMeasurement(Eigen::VectorXd c) : c_(std::move(c)) { RequireDirection(c_); }

TiltedMoments ProjectedMeasurement::Tilt(double y, double mean, double variance) const {
  return QuadratureTilt(y, mean, variance);
}

TiltedMoments ProjectedMeasurement::QuadratureTilt(double y, double mean, double variance) const {
  IDENT_REQUIRE(IsValidOutput(y), "y = {} is not a possible reading of the {} measurement", y, name());
  IDENT_REQUIRE(variance > 0 && std::isfinite(variance) && std::isfinite(mean),
                "prior mean = {}, variance = {}; need finite mean and variance > 0", mean, variance);
  const double sd = std::sqrt(variance);
  const Pieces p = SupportPieces(y);
  auto log_f = [&](double s) { return LogLikelihoodScalar(y, s) - 0.5 * (s - mean) * (s - mean) / variance; };
  // Window for the mode search: the prior's ±40 sd clipped to the support (or the support's near end).
  double a = std::max(p.lo, mean - 40 * sd), b = std::min(p.hi, mean + 40 * sd);
  if (a >= b) {
    if (p.lo >= mean) {
      a = p.lo;
      b = std::min(p.hi, p.lo + 40 * sd);
    } else {
      b = p.hi;
      a = std::max(p.lo, p.hi - 40 * sd);
    }
  }
  // The likelihood can pull the mode far outside that window (a narrow prior far from the reading). The
  // log integrand is concave, so while it still rises at an end of the window the mode lies beyond it:
  // move that end out, doubling the step, until the integrand falls or the support ends.
  const double centre = 0.5 * (a + b);
  for (int side : {1, -1}) {
    double& end = side > 0 ? b : a;
    const double bound = side > 0 ? p.hi : p.lo;
    double inner = centre, step = 40 * sd;
    for (int i = 0; i < 80 && end != bound && log_f(end) > log_f(inner); ++i) {
      inner = end;
      step *= 2;
      end = side > 0 ? std::min(bound, end + step) : std::max(bound, end - step);
    }
  }
  // Golden-section search for the mode of the concave log integrand.
  const double g = (std::sqrt(5.0) - 1) / 2;
  double x1 = b - g * (b - a), x2 = a + g * (b - a), f1 = log_f(x1), f2 = log_f(x2);
  for (int i = 0; i < 200 && b - a > 1e-13 * (1 + std::abs(a) + std::abs(b)); ++i) {
    if (f1 < f2) {
      a = x1;
      x1 = x2;
      f1 = f2;
      x2 = a + g * (b - a);
      f2 = log_f(x2);
    } else {
      b = x2;
      x2 = x1;
      f2 = f1;
      x1 = b - g * (b - a);
      f1 = log_f(x1);
    }
  }
  const double mode = 0.5 * (a + b);
  const double log_peak = std::max({log_f(mode), f1, f2});
  if (!std::isfinite(log_peak)) return {};
  // The tilted density is in LC(1/variance) (Thm 1, product), so its mass beyond 12 sd of the mode
  // is below e^(−72) of the total.
  std::array<double, 6> cuts{};
  int n = 0;
  const double lo = std::max(p.lo, mode - 12 * sd), hi = std::min(p.hi, mode + 12 * sd);
  cuts[n++] = lo;
  std::array<double, 3> kinks = p.kinks;
  std::sort(kinks.begin(), kinks.end(), [](double u, double v) { return std::isnan(v) ? !std::isnan(u) : u < v; });
  for (double k : kinks)
    if (!std::isnan(k) && k > lo && k < hi) cuts[n++] = k;
  cuts[n++] = hi;
  using GK = boost::math::quadrature::gauss_kronrod<double, 31>;
  auto integrate = [&](auto&& fn) {
    double sum = 0;
    for (int i = 0; i + 1 < n; ++i) sum += GK::integrate(fn, cuts[i], cuts[i + 1], 12, 1e-13);
    return sum;
  };
  auto w = [&](double s) { return std::exp(log_f(s) - log_peak); };
  const double z = integrate(w);
  if (!(z > 0)) return {};
  const double m1 = integrate([&](double s) { return s * w(s); }) / z;
  const double var = integrate([&](double s) { return (s - m1) * (s - m1) * w(s); }) / z;
  return {std::log(z) + log_peak - 0.5 * std::log(2 * std::numbers::pi * variance), m1, var, true};
}

// ---- Gaussian -------------------------------------------------------------------------------------

GaussianMeasurement::GaussianMeasurement(Eigen::VectorXd c, double noise_variance)
    : ProjectedMeasurement(std::move(c)), r_(noise_variance) {
  IDENT_REQUIRE(r_ > 0 && std::isfinite(r_), "noise_variance = {}; need > 0", r_);
}

double GaussianMeasurement::LogLikelihoodScalar(double y, double s) const {
  return -0.5 * (y - s) * (y - s) / r_ - 0.5 * std::log(2 * std::numbers::pi * r_);
}

TiltedMoments GaussianMeasurement::Tilt(double y, double mean, double variance) const {
  const double s = variance + r_;  // scalar Kalman update
  return {-0.5 * (y - mean) * (y - mean) / s - 0.5 * std::log(2 * std::numbers::pi * s),
          mean + variance / s * (y - mean), variance * r_ / s, true};
}

// ---- Interval readings ----------------------------------------------------------------------------

double IntervalMeasurement::LogLikelihoodScalar(double y, double s) const {
  const auto [lo, hi] = Interval(y);
  return (s >= lo && s <= hi) ? 0.0 : -kInf;
}

TiltedMoments IntervalMeasurement::Tilt(double y, double mean, double variance) const {
  IDENT_REQUIRE(IsValidOutput(y), "y = {} is not a possible reading of the {} measurement", y, name());
  const auto [lo, hi] = Interval(y);
  return TruncatedNormalMoments(mean, variance, lo, hi);
}

ProjectedMeasurement::Pieces IntervalMeasurement::SupportPieces(double y) const {
  const auto [lo, hi] = Interval(y);
  Pieces p;
  p.lo = lo;
  p.hi = hi;
  return p;
}

ThresholdSensor::ThresholdSensor(Eigen::VectorXd c, double threshold)
    : IntervalMeasurement(std::move(c)), threshold_(threshold) {
  IDENT_REQUIRE(threshold_ > 0 && std::isfinite(threshold_), "threshold = {}; need > 0", threshold_);
}

std::pair<double, double> ThresholdSensor::Interval(double y) const {
  IDENT_REQUIRE(IsValidOutput(y), "threshold sensor reading y = {}; need -1, 0 or 1", y);
  if (y > 0) return {threshold_, kInf};
  if (y < 0) return {-kInf, -threshold_};
  return {-threshold_, threshold_};
}

double ThresholdSensor::Measure(const Eigen::Ref<const Eigen::VectorXd>& x) const {
  const double s = c().dot(x);
  return std::abs(s) >= threshold_ ? (s > 0 ? 1.0 : -1.0) : 0.0;
}

UniformQuantizer::UniformQuantizer(Eigen::VectorXd c, double step) : IntervalMeasurement(std::move(c)), step_(step) {
  IDENT_REQUIRE(step_ > 0 && std::isfinite(step_), "quantizer step = {}; need > 0", step_);
}

bool UniformQuantizer::IsValidOutput(double y) const {
  if (!std::isfinite(y)) return false;
  const double k = y / step_;
  return std::abs(k - std::round(k)) <= 1e-9 * (1 + std::abs(k));
}

std::pair<double, double> UniformQuantizer::Interval(double y) const {
  IDENT_REQUIRE(IsValidOutput(y), "quantizer reading y = {} is not a multiple of the step {}", y, step_);
  return {y - step_ / 2, y + step_ / 2};
}

double UniformQuantizer::Measure(const Eigen::Ref<const Eigen::VectorXd>& x) const {
  return step_ * std::round(c().dot(x) / step_);
}

// ---- Example 1 ------------------------------------------------------------------------------------

OptimalQuantizer::OptimalQuantizer(Eigen::VectorXd c) : ProjectedMeasurement(std::move(c)) {}

double OptimalQuantizer::Density(double x) {
  const double a = std::abs(x);
  if (a <= 0.5) return std::exp2(-4 * a * a);  // [1, example 1]
  if (a <= 1.0) return 1.0 - std::exp2(-4 * (1 - a) * (1 - a));
  return 0.0;
}

double OptimalQuantizer::LogDensity(double x) {
  const double a = std::abs(x);
  if (a <= 0.5) return -4 * std::log(2.0) * a * a;
  if (a < 1.0) return std::log1p(-std::exp2(-4 * (1 - a) * (1 - a)));
  return -kInf;
}

ProjectedMeasurement::Pieces OptimalQuantizer::SupportPieces(double y) const {
  Pieces p;
  p.lo = y - 1;
  p.hi = y + 1;
  p.kinks = {y - 0.5, y, y + 0.5};
  return p;
}

// ---- Laplace --------------------------------------------------------------------------------------

LaplaceMeasurement::LaplaceMeasurement(Eigen::VectorXd c, double scale)
    : ProjectedMeasurement(std::move(c)), b_(scale) {
  IDENT_REQUIRE(b_ > 0 && std::isfinite(b_), "Laplace scale = {}; need > 0", b_);
}

double LaplaceMeasurement::LogLikelihoodScalar(double y, double s) const {
  return -std::abs(y - s) / b_ - std::log(2 * b_);
}

ProjectedMeasurement::Pieces LaplaceMeasurement::SupportPieces(double y) const {
  Pieces p;
  p.kinks[0] = y;
  return p;
}

}  // namespace ident::models
