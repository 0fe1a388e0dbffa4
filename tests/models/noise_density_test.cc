// models/noise_density.h: the standard densities (normalised, their MAD consistency and standard
// deviation by independent quadrature) and the tilted residual moments of the closed forms and the
// Gauss–Legendre rule against adaptive Gauss–Kronrod quadrature.
#include "models/noise_density.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <boost/math/quadrature/gauss_kronrod.hpp>

#include "common/error.h"

namespace ident::models {
namespace {

const char* const kFamilies[] = {"gaussian",     "laplace",      "huber",        "huber:0.5", "logistic",
                                 "gengauss:1.1", "gengauss:1.3", "gengauss:1.5", "gengauss:2"};

double Integrate(const LogConcaveNoise& f, double power, double lo, double hi) {
  using GK = boost::math::quadrature::gauss_kronrod<double, 61>;
  auto g = [&](double u) { return std::pow(std::abs(u), power) * std::exp(f.LogDensity(u)); };
  // Split at 0 and at the Huber corners, where the integrand has kinks.
  double sum = 0;
  const double cuts[] = {lo, -1.345, -0.5, 0.0, 0.5, 1.345, hi};
  for (int i = 0; i + 1 < 7; ++i) {
    const double a = std::max(lo, cuts[i]), b = std::min(hi, cuts[i + 1]);
    if (b > a) sum += GK::integrate(g, a, b, 15, 1e-14);
  }
  return sum;
}

TEST(LogConcaveNoise, DensityIsNormalisedWithTheStatedMedianAndStandardDeviation) {
  for (const char* spec : kFamilies) {
    SCOPED_TRACE(spec);
    const LogConcaveNoise f = LogConcaveNoise::Parse(spec);
    EXPECT_NEAR(Integrate(f, 0, -200, 200), 1.0, 1e-10);
    const double m = f.median_abs();
    EXPECT_NEAR(Integrate(f, 0, -m, m), 0.5, 1e-10);
    EXPECT_NEAR(std::sqrt(Integrate(f, 2, -200, 200)), f.standard_deviation(), 1e-9);
  }
}

TEST(LogConcaveNoise, ScoreIsMinusTheDerivativeOfTheLogDensity) {
  for (const char* spec : kFamilies) {
    SCOPED_TRACE(spec);
    const LogConcaveNoise f = LogConcaveNoise::Parse(spec);
    for (double u : {-7.0, -2.1, -0.3, 0.4, 1.9, 6.0}) {
      const double h = 1e-6;
      EXPECT_NEAR(f.Score(u), -(f.LogDensity(u + h) - f.LogDensity(u - h)) / (2 * h), 1e-6) << u;
    }
  }
}

TEST(LogConcaveNoise, WeightIsOneForTypicalResidualsAndFallsForOutliers) {
  const LogConcaveNoise laplace = LogConcaveNoise::Parse("laplace");
  EXPECT_EQ(laplace.Weight(0.1), 1.0);
  EXPECT_NEAR(laplace.Weight(5 * std::log(2.0)), 0.2, 1e-12);  // 5 MADs
  EXPECT_NEAR(laplace.Weight(-1000.0), std::log(2.0) / 1000, 1e-15);
  const LogConcaveNoise gaussian = LogConcaveNoise::Parse("gaussian");
  EXPECT_EQ(gaussian.Weight(1e6), 1.0);  // least squares: every sample alike
  const LogConcaveNoise huber = LogConcaveNoise::Parse("huber:1.345");
  EXPECT_NEAR(huber.Weight(13.45), 0.1, 1e-12);  // beyond the corner: k/|u|
}

// The closed forms (gaussian, laplace, huber), the logistic rule and the gengauss quadrature against
// adaptive Gauss–Kronrod on the tilted density, from outliers far on either side to vague priors.
TEST(LogConcaveNoise, ResidualMomentsMatchQuadrature) {
  for (const char* spec : kFamilies) {
    const LogConcaveNoise f = LogConcaveNoise::Parse(spec);
    for (double a : {-2000.0, -40.0, -3.0, -0.5, 0.0, 0.7, 4.0, 60.0, 300.0}) {
      for (double v : {1e-4, 0.01, 1.0, 10.0, 1e4}) {
        SCOPED_TRACE(std::string(spec) + " a=" + std::to_string(a) + " v=" + std::to_string(v));
        const TiltedMoments t = f.ResidualMoments(a, v);
        const TiltedMoments q = f.QuadratureResidualMoments(a, v);
        ASSERT_TRUE(t.ok);
        ASSERT_TRUE(q.ok);
        const double sd = std::sqrt(q.variance);
        EXPECT_NEAR(t.mean, q.mean, 1e-8 * sd + 1e-12 * std::abs(q.mean));
        EXPECT_NEAR(t.variance, q.variance, 1e-7 * q.variance);
        EXPECT_NEAR(t.log_normalizer, q.log_normalizer, 1e-8);
      }
    }
  }
}

// An independent reference for the tilted moments: the mode of the log-concave f(r)·N(r; a, v) by bisection
// on its derivative −ψ(r) − (r − a)/v over [min(0, a), max(0, a)], then adaptive Gauss–Kronrod (61 points,
// 1e-12) on 16 panels over the mode ± min(40√v, 80), split at the kinks of f (0, ±k). The density is in
// LC(1/v), so the mass beyond 40√v is below e^{−800} of its peak's, and f's tails fall by e^{−40} over 80.
TiltedMoments FineReference(const LogConcaveNoise& f, double a, double v) {
  double lo = std::min(0.0, a), hi = std::max(0.0, a);
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    (-f.Score(mid) - (mid - a) / v > 0 ? lo : hi) = mid;
  }
  const double mode = 0.5 * (lo + hi), sd = std::sqrt(v);
  auto log_h = [&](double r) { return f.LogDensity(r) - 0.5 * (r - a) * (r - a) / v; };
  const double peak = log_h(mode);
  const double half = std::min(40 * sd, 80.0);  // beyond 80 every f here has fallen by e^{−40}
  std::vector<double> cuts;
  for (int i = -8; i <= 8; ++i) cuts.push_back(mode + half * i / 8);
  for (double k : {0.0, f.shape(), -f.shape()})
    if (k > cuts.front() && k < cuts.back()) cuts.push_back(k);
  std::sort(cuts.begin(), cuts.end());
  using GK = boost::math::quadrature::gauss_kronrod<double, 61>;
  auto integrate = [&](auto&& g) {
    double sum = 0;
    for (std::size_t i = 0; i + 1 < cuts.size(); ++i)
      if (cuts[i + 1] > cuts[i]) sum += GK::integrate(g, cuts[i], cuts[i + 1], 10, 1e-12);
    return sum;
  };
  const double z = integrate([&](double r) { return std::exp(log_h(r) - peak); });
  const double m1 = integrate([&](double r) { return (r - mode) * std::exp(log_h(r) - peak); }) / z;
  const double m2 =
      integrate([&](double r) { return (r - mode - m1) * (r - mode - m1) * std::exp(log_h(r) - peak); }) / z;
  return {peak + std::log(z) - 0.5 * std::log(2 * M_PI * v), mode + m1, m2, true};
}

// The fast moments (the closed forms with their continued-fraction tails, the Gauss–Hermite rules and
// the graded rules) to 1e-10 of an adaptive Gauss–Kronrod reference over a fine grid of (a, v): |a| from 0
// to past the outliers, v from the steady state (1e-4) past each rule's switch-over to vague priors.
TEST(LogConcaveNoise, FastResidualMomentsAgreeWithQuadratureTo1e10) {
  std::vector<double> as, vs;
  for (double a = 0; a < 12; a += 1.3) as.push_back(a);
  for (double a : {0.01, 0.05, 15.0, 40.0, 300.0, 2000.0}) as.push_back(a);
  for (double lv = -4; lv <= 2.01; lv += 0.5) vs.push_back(std::pow(10.0, lv));
  for (const char* spec : kFamilies) {
    const LogConcaveNoise f = LogConcaveNoise::Parse(spec);
    double worst = 0;
    std::string worst_at;
    for (double a0 : as) {
      for (double sign : {1.0, -1.0}) {
        const double a = sign * a0;
        for (double v : vs) {
          const TiltedMoments t = f.ResidualMoments(a, v);
          const TiltedMoments q = FineReference(f, a, v);
          SCOPED_TRACE(std::string(spec) + " a=" + std::to_string(a) + " v=" + std::to_string(v));
          ASSERT_TRUE(t.ok);
          ASSERT_TRUE(q.ok);
          const double e_mean = std::abs(t.mean - q.mean) / (std::sqrt(q.variance) + std::abs(q.mean));
          const double e_var = std::abs(t.variance - q.variance) / q.variance;
          const double e_log = std::abs(t.log_normalizer - q.log_normalizer) / (1 + std::abs(q.log_normalizer));
          EXPECT_LE(e_mean, 1e-10);
          EXPECT_LE(e_var, 1e-10);
          EXPECT_LE(e_log, 1e-10);
          if (std::max({e_mean, e_var, e_log}) > worst) {
            worst = std::max({e_mean, e_var, e_log});
            worst_at = "a = " + std::to_string(a) + ", v = " + std::to_string(v);
          }
        }
      }
    }
    std::printf("%s: worst relative difference %.1e at %s\n", spec, worst, worst_at.c_str());
  }
}

// gengauss with the kink of |r|^p inside a narrow prior (|a| < 12√v, √v ≤ 0.75: the half-line Gauss rules)
// and with an outlier far beyond it (the mode-centred Gauss–Hermite rule): to 1e−10 of the reference, at
// standardised residuals a/√v between the rules' grid points and for shapes where s^{2p} is not smooth.
TEST(LogConcaveNoise, GengaussMomentsAroundTheKinkAgreeWithQuadratureTo1e10) {
  for (const char* spec :
       {"gengauss:1", "gengauss:1.1", "gengauss:1.3", "gengauss:1.5", "gengauss:1.75", "gengauss:2"}) {
    const LogConcaveNoise f = LogConcaveNoise::Parse(spec);
    std::vector<std::pair<double, double>> cases;  // (a, v)
    for (double sd : {1e-3, 0.01, 0.05, 0.1, 0.15, 0.2, 0.25, 0.3, 0.4, 0.45, 0.5, 0.6, 0.7, 0.75})
      for (double alpha = -11.9; alpha < 12; alpha += 0.37) cases.emplace_back(alpha * sd, sd * sd);
    for (double a : {4.0, 10.0, 50.0, 300.0})
      for (double v : {0.3, 1.0, 3.0}) cases.emplace_back(a, v);
    double worst = 0;
    for (const auto& [a, v] : cases) {
      SCOPED_TRACE(std::string(spec) + " a=" + std::to_string(a) + " v=" + std::to_string(v));
      const TiltedMoments t = f.ResidualMoments(a, v);
      const TiltedMoments q = FineReference(f, a, v);
      ASSERT_TRUE(t.ok);
      const double e = std::max({std::abs(t.mean - q.mean) / (std::sqrt(q.variance) + std::abs(q.mean)),
                                 std::abs(t.variance - q.variance) / q.variance,
                                 std::abs(t.log_normalizer - q.log_normalizer) / (1 + std::abs(q.log_normalizer))});
      EXPECT_LE(e, 1e-10);
      worst = std::max(worst, e);
    }
    std::printf("%s: worst relative difference %.1e\n", spec, worst);
  }
}

// Gaussian: a product of Gaussians in closed form, checked by hand.
TEST(LogConcaveNoise, GaussianMomentsAreTheConjugateUpdate) {
  const TiltedMoments t = LogConcaveNoise::Parse("gaussian").ResidualMoments(2.0, 3.0);
  EXPECT_DOUBLE_EQ(t.mean, 2.0 / 4.0);
  EXPECT_DOUBLE_EQ(t.variance, 3.0 / 4.0);
  EXPECT_NEAR(t.log_normalizer, -0.5 * 4.0 / 4.0 - 0.5 * std::log(2 * M_PI * 4.0), 1e-14);
}

TEST(LogConcaveNoise, ParseNamesTheBadSpec) {
  EXPECT_EQ(LogConcaveNoise::Parse("huber").shape(), 1.345);
  EXPECT_EQ(LogConcaveNoise::Parse("huber:2").ToString(), "huber:2");
  EXPECT_EQ(LogConcaveNoise::Parse("gengauss:1.5").family(), LogConcaveNoise::Family::kGeneralizedGaussian);
  for (const char* bad : {"cauchy", "huber:x", "huber:-1", "gengauss", "gengauss:0.5", "gengauss:3", "laplace:2", ""}) {
    SCOPED_TRACE(bad);
    EXPECT_THROW(LogConcaveNoise::Parse(bad), InvalidArgument);
  }
}

}  // namespace
}  // namespace ident::models
