// Tilted-Gaussian moments of the measurement functions: closed forms against adaptive quadrature,
// quadrature against an independent fine trapezoid rule, and the paper's example-1 quantiser.
#include <cmath>
#include <numbers>
#include <random>

#include <gtest/gtest.h>

#include "ident/common/error.h"
#include "models/measurement.h"

namespace ident::models {
namespace {

const Eigen::VectorXd kC = Eigen::VectorXd::Ones(1);

// Independent reference: composite trapezoid on a very fine grid over mean ± 14 sd (clipped).
TiltedMoments TrapezoidTilt(const ProjectedMeasurement& m, double y, double mean, double var) {
  const double sd = std::sqrt(var);
  const int n = 400000;
  const double a = mean - 14 * sd, b = mean + 14 * sd, h = (b - a) / n;
  double z = 0, s1 = 0, s2 = 0;
  for (int i = 0; i <= n; ++i) {
    const double s = a + i * h;
    const double w = (i == 0 || i == n ? 0.5 : 1.0) *
                     std::exp(m.LogLikelihoodScalar(y, s) - 0.5 * (s - mean) * (s - mean) / var);
    z += w; s1 += w * s; s2 += w * s * s;
  }
  const double mu = s1 / z;
  return {std::log(z * h / std::sqrt(2 * std::numbers::pi * var)), mu, s2 / z - mu * mu, true};
}

TEST(TiltedMoments, ThresholdClosedFormEqualsQuadratureTo1e10) {
  ThresholdSensor sensor(kC, 1.0);
  for (double y : {-1.0, 0.0, 1.0})
    for (double mean : {-3.0, -0.9, 0.0, 0.4, 1.2, 5.0})
      for (double var : {0.01, 0.3, 1.0, 4.0}) {
        const TiltedMoments a = sensor.Tilt(y, mean, var);
        const TiltedMoments b = sensor.QuadratureTilt(y, mean, var);
        ASSERT_TRUE(a.ok && b.ok) << y << " " << mean << " " << var;
        EXPECT_NEAR(a.mean, b.mean, 1e-10 * std::max(1.0, std::abs(b.mean))) << y << " " << mean << " " << var;
        EXPECT_NEAR(a.variance, b.variance, 1e-10 * std::max(1.0, b.variance)) << y << " " << mean << " " << var;
        EXPECT_NEAR(a.log_normalizer, b.log_normalizer, 1e-10 * std::max(1.0, std::abs(b.log_normalizer)));
      }
}

TEST(TiltedMoments, QuantizerClosedFormEqualsQuadratureTo1e10IncludingNarrowTailCells) {
  UniformQuantizer q(kC, 0.25);
  for (double y : {-2.0, -0.25, 0.0, 0.5, 3.0})
    for (double mean : {-1.0, 0.1, 0.7})
      for (double var : {0.001, 0.05, 2.0}) {
        const TiltedMoments a = q.Tilt(y, mean, var), b = q.QuadratureTilt(y, mean, var);
        ASSERT_TRUE(a.ok && b.ok);
        EXPECT_NEAR(a.mean, b.mean, 1e-10 * std::max(1.0, std::abs(b.mean))) << y << " " << mean << " " << var;
        EXPECT_NEAR(a.variance, b.variance, 1e-10 * std::max(1.0, b.variance)) << y << " " << mean << " " << var;
        EXPECT_NEAR(a.log_normalizer, b.log_normalizer, 1e-10 * std::max(1.0, std::abs(b.log_normalizer)));
      }
}

TEST(TiltedMoments, FarTailHalfLineMatchesMillsRatioAsymptotics) {
  // N(0,1) truncated to [a, ∞) for large a: mean = a + 1/a − 2/a³ + O(a⁻⁵), var = 1/a² − 6/a⁴ + O(a⁻⁶).
  for (double a : {40.0, 100.0, 1000.0}) {
    const TiltedMoments t = TruncatedNormalMoments(0.0, 1.0, a, std::numeric_limits<double>::infinity());
    ASSERT_TRUE(t.ok);
    EXPECT_NEAR(t.mean, a + 1 / a - 2 / (a * a * a), 20 / std::pow(a, 5));
    EXPECT_NEAR(t.variance, 1 / (a * a) - 6 / std::pow(a, 4), 60 / std::pow(a, 6));
    EXPECT_NEAR(t.log_normalizer, -0.5 * a * a - std::log(a * std::sqrt(2 * std::numbers::pi)), 2 / (a * a));
  }
}

TEST(TiltedMoments, GaussianClosedFormEqualsQuadratureTo1e10) {
  GaussianMeasurement g(kC, 0.2);
  for (double mean : {-1.0, 0.5}) {
    const TiltedMoments a = g.Tilt(0.3, mean, 0.7), b = g.QuadratureTilt(0.3, mean, 0.7);
    EXPECT_NEAR(a.mean, b.mean, 1e-10);
    EXPECT_NEAR(a.variance, b.variance, 1e-10);
    EXPECT_NEAR(a.log_normalizer, b.log_normalizer, 1e-10);
  }
}

TEST(TiltedMoments, QuadratureForLaplaceAndOptimalQuantizerMatchesFineTrapezoid) {
  LaplaceMeasurement lap(kC, 0.3);
  OptimalQuantizer oq(kC);
  for (double mean : {-0.7, 0.2, 1.9}) {
    for (const ProjectedMeasurement* m : {static_cast<const ProjectedMeasurement*>(&lap),
                                          static_cast<const ProjectedMeasurement*>(&oq)}) {
      const double y = 1.0;
      const TiltedMoments a = m->Tilt(y, mean, 0.5), b = TrapezoidTilt(*m, y, mean, 0.5);
      ASSERT_TRUE(a.ok);
      EXPECT_NEAR(a.mean, b.mean, 1e-8) << m->name() << " " << mean;
      EXPECT_NEAR(a.variance, b.variance, 1e-8) << m->name() << " " << mean;
      EXPECT_NEAR(a.log_normalizer, b.log_normalizer, 1e-8) << m->name() << " " << mean;
    }
  }
}

TEST(TiltedMoments, ReadingFarInTheTailStaysFiniteInLogSpaceAndBadInputThrows) {
  ThresholdSensor sensor(kC, 1.0);
  const TiltedMoments t = sensor.Tilt(1.0, -1e6, 1e-6);  // threshold 10^9 sd above the prior mean
  ASSERT_TRUE(t.ok);
  EXPECT_NEAR(t.mean, 1.0, 1e-9);                          // mass piles up just past the threshold
  EXPECT_GE(t.variance, 0.0);
  EXPECT_LT(t.variance, 1e-20);
  EXPECT_LT(t.log_normalizer, -4.9e17);                    // ≈ −a²/2, a = 10^9
  EXPECT_THROW(sensor.Tilt(2.0, 0.0, 1.0), ident::InvalidArgument);
  EXPECT_THROW(sensor.Tilt(0.0, 0.0, -1.0), ident::InvalidArgument);
  EXPECT_THROW(ThresholdSensor(kC, 0.0), ident::InvalidArgument);
}

TEST(OptimalQuantizer, PartitionOfUnityAndStrongLogConcavity8Ln2) {
  for (double x = -3; x <= 3; x += 0.0137) {
    double sum = 0;
    for (int k = -5; k <= 5; ++k) sum += OptimalQuantizer::Density(x - k);
    EXPECT_NEAR(sum, 1.0, 1e-14) << x;
  }
  // log f(x) + 4 ln2 x² is concave on the support (−1, 1): second differences ≤ 0.
  auto g = [](double x) { return OptimalQuantizer::LogDensity(x) + 4 * std::log(2.0) * x * x; };
  const double h = 1e-3;
  for (double x = -0.99; x <= 0.99; x += 0.003) EXPECT_LE(g(x + h) - 2 * g(x) + g(x - h), 1e-9) << x;
  // ... and the strength is tight: log f + (4 ln2 + 0.1) x² is not concave at x = 0.
  auto g2 = [](double x) { return OptimalQuantizer::LogDensity(x) + (4 * std::log(2.0) + 0.1) * x * x; };
  EXPECT_GT(g2(h) - 2 * g2(0) + g2(-h), 0);
}

TEST(OptimalQuantizer, PosteriorVarianceAfterNReadingsIsBelowOneOver8NLn2) {
  // Flat prior, x ~ U(0, 1), readings y = k with probability f(x − k). The posterior ∝ Π f(x − y_i) is
  // in LC(8 n ln 2), so by Theorem 2 its variance ≤ 1/(8 n ln 2). Variance by fine midpoint quadrature.
  std::mt19937_64 rng(20060724);
  std::uniform_real_distribution<double> unif(0.0, 1.0);
  const int grid = 6000;
  for (int trial = 0; trial < 20; ++trial) {
    const double x = unif(rng);
    std::vector<double> ys;
    for (int n = 1; n <= 20; ++n) {
      const double k = std::floor(x);
      ys.push_back(unif(rng) < OptimalQuantizer::Density(x - k) ? k : k + 1);
      double z = 0, s1 = 0, s2 = 0;
      for (int i = 0; i < grid; ++i) {
        const double t = -1.0 + 3.0 * (i + 0.5) / grid;
        double w = 1;
        for (double y : ys) w *= OptimalQuantizer::Density(t - y);
        z += w; s1 += w * t; s2 += w * t * t;
      }
      const double var = s2 / z - (s1 / z) * (s1 / z);
      EXPECT_LE(var, 1.0 / (8 * n * std::log(2.0)) * (1 + 1e-6)) << "trial " << trial << " n " << n;
    }
  }
}

}  // namespace
}  // namespace ident::models
