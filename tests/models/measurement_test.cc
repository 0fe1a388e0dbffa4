// Tilted-Gaussian moments of the measurement functions: closed forms against adaptive quadrature,
// quadrature against an independent fine trapezoid rule, and the paper's example-1 quantiser.
#include <cmath>
#include <numbers>
#include <random>
#include <string>
#include <tuple>

#include <gtest/gtest.h>

#include "common/error.h"
#include "common/step_report.h"
#include "ident/observers/lc_gaussian_filter.h"
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
    const double w =
        (i == 0 || i == n ? 0.5 : 1.0) * std::exp(m.LogLikelihoodScalar(y, s) - 0.5 * (s - mean) * (s - mean) / var);
    z += w;
    s1 += w * s;
    s2 += w * s * s;
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

TEST(TiltedMoments, QuadratureFindsAModeFarOutsideThePriorsWindow) {
  // A narrow prior far from the reading: the posterior mode lies hundreds of prior widths from the prior
  // mean (Gaussian product: mean = (σ²·μ + v·y)/(σ² + v), variance = σ²v/(σ² + v)).
  GaussianMeasurement g(kC, 1.0);
  for (double mean : {-300.0, 300.0, 2.0e4})
    for (double var : {0.03, 1.0}) {
      const TiltedMoments a = g.Tilt(0.0, mean, var), b = g.QuadratureTilt(0.0, mean, var);
      ASSERT_TRUE(a.ok && b.ok) << mean << " " << var;
      EXPECT_NEAR(b.mean, mean / (1 + var), 1e-9 * std::abs(mean)) << mean << " " << var;
      EXPECT_NEAR(b.variance, var / (1 + var), 1e-9) << mean << " " << var;
      EXPECT_NEAR(b.log_normalizer, a.log_normalizer, 1e-9 * std::abs(a.log_normalizer)) << mean << " " << var;
    }
}

TEST(TiltedMoments, QuadratureForLaplaceAndOptimalQuantizerMatchesFineTrapezoid) {
  LaplaceMeasurement lap(kC, 0.3);
  OptimalQuantizer oq(kC);
  for (double mean : {-0.7, 0.2, 1.9}) {
    for (const ProjectedMeasurement* m :
         {static_cast<const ProjectedMeasurement*>(&lap), static_cast<const ProjectedMeasurement*>(&oq)}) {
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
  EXPECT_NEAR(t.mean, 1.0, 1e-9);  // mass piles up just past the threshold
  EXPECT_GE(t.variance, 0.0);
  EXPECT_LT(t.variance, 1e-20);
  EXPECT_LT(t.log_normalizer, -4.9e17);  // ≈ −a²/2, a = 10^9
  EXPECT_THROW(sensor.Tilt(2.0, 0.0, 1.0), ident::InvalidArgument);
  EXPECT_THROW(sensor.Tilt(0.0, 0.0, -1.0), ident::InvalidArgument);
  EXPECT_THROW(ThresholdSensor(kC, 0.0), ident::InvalidArgument);
}

// Degenerate intervals (the lc_gaussian_fuzzer finding: a = b = 0 recursed for ever). An interval
// without mass has no moments: ok = false and NaN fields, never NaN moments with ok = true.
void ExpectNoMass(const TiltedMoments& t, const std::string& what) {
  EXPECT_FALSE(t.ok) << what;
  EXPECT_TRUE(std::isnan(t.log_normalizer) && std::isnan(t.mean) && std::isnan(t.variance)) << what;
}

TEST(TruncatedMoments, EmptyPointAndNanIntervalsHaveNoMass) {
  const double inf = std::numeric_limits<double>::infinity(), nan = std::numeric_limits<double>::quiet_NaN();
  ExpectNoMass(StandardTruncatedMoments(0.0, 0.0), "a = b = 0");
  ExpectNoMass(StandardTruncatedMoments(-0.0, 0.0), "a = -0, b = +0");
  ExpectNoMass(StandardTruncatedMoments(0.0, -0.0), "a = +0, b = -0");
  ExpectNoMass(StandardTruncatedMoments(1.5, 1.5), "a = b = 1.5");
  ExpectNoMass(StandardTruncatedMoments(-2.0, -2.0), "a = b = -2");
  ExpectNoMass(StandardTruncatedMoments(0.5, -0.5), "a > b around 0 (reflects onto itself)");
  ExpectNoMass(StandardTruncatedMoments(3.0, 1.0), "a > b > 0");
  ExpectNoMass(StandardTruncatedMoments(-1.0, -3.0), "0 > a > b");
  ExpectNoMass(StandardTruncatedMoments(nan, 1.0), "a NaN");
  ExpectNoMass(StandardTruncatedMoments(-1.0, nan), "b NaN");
  ExpectNoMass(StandardTruncatedMoments(nan, nan), "both NaN");
  ExpectNoMass(StandardTruncatedMoments(inf, inf), "a = b = +inf");
  ExpectNoMass(StandardTruncatedMoments(-inf, -inf), "a = b = -inf");
  ExpectNoMass(StandardTruncatedMoments(inf, -inf), "a = +inf, b = -inf");
  // Z = Φ(5e-324) − Φ(0) ≈ 2e-324 underflows: no mass in double precision.
  ExpectNoMass(StandardTruncatedMoments(0.0, 5e-324), "Z underflows");
}

TEST(TruncatedMoments, InfiniteBoundsGiveTheClosedForms) {
  const double inf = std::numeric_limits<double>::infinity();
  // The whole line: N(0, 1) itself.
  const TiltedMoments all = StandardTruncatedMoments(-inf, inf);
  ASSERT_TRUE(all.ok);
  EXPECT_NEAR(all.log_normalizer, 0.0, 1e-15);
  EXPECT_NEAR(all.mean, 0.0, 1e-15);
  EXPECT_NEAR(all.variance, 1.0, 1e-15);
  // Half-normal: Z = 1/2, mean ±√(2/π), variance 1 − 2/π.
  const double half_mean = std::sqrt(2 / std::numbers::pi), half_var = 1 - 2 / std::numbers::pi;
  for (const auto& [a, b, sign] :
       {std::tuple{0.0, inf, 1.0}, std::tuple{-inf, 0.0, -1.0}, std::tuple{-inf, -0.0, -1.0}}) {
    const TiltedMoments t = StandardTruncatedMoments(a, b);
    ASSERT_TRUE(t.ok) << a << " " << b;
    EXPECT_NEAR(t.log_normalizer, std::log(0.5), 1e-14) << a << " " << b;
    EXPECT_NEAR(t.mean, sign * half_mean, 1e-14) << a << " " << b;
    EXPECT_NEAR(t.variance, half_var, 1e-14) << a << " " << b;
  }
  // A lower tail (−∞, −40]: the mirror image of the Mills-ratio asymptotics above.
  const TiltedMoments low = StandardTruncatedMoments(-inf, -40.0);
  ASSERT_TRUE(low.ok);
  EXPECT_NEAR(low.mean, -(40 + 1 / 40.0 - 2 / 64000.0), 20 / std::pow(40.0, 5));
}

TEST(TruncatedMoments, IntervalThatCollapsesWhenStandardisedHasNoMassAndTheFilterRejectsTheStep) {
  // N(0, 1e300) on [0, 1e-200]: standardised (0/1e150, 1e-200/1e150) = (0, 0), the finding's a = b = 0.
  ExpectNoMass(TruncatedNormalMoments(0.0, 1e300, 0.0, 1e-200), "collapsed to a = b = 0");
  ExpectNoMass(TruncatedNormalMoments(0.0, 1.0, 2.0, 2.0), "lo = hi");
  ExpectNoMass(TruncatedNormalMoments(0.0, 1.0, 2.0, 1.0), "lo > hi");
  ExpectNoMass(TruncatedNormalMoments(0.0, 1.0, std::numeric_limits<double>::quiet_NaN(), 1.0), "lo NaN");
  EXPECT_THROW(TruncatedNormalMoments(0.0, 0.0, 0.0, 1.0), ident::InvalidArgument);  // the prior is checked
  // A threshold sensor with T = 1e-200 reading 0 under the prior N(0, 1e300): the same collapse.
  ThresholdSensor sensor(kC, 1e-200);
  ExpectNoMass(sensor.Tilt(0.0, 0.0, 1e300), "threshold sensor");
  // A quantiser cell that rounds to a point: y = 1e300, Δ = 1 gives [y − ½, y + ½] = [y, y].
  UniformQuantizer q(kC, 1.0);
  ASSERT_TRUE(q.IsValidOutput(1e300));
  ExpectNoMass(q.Tilt(1e300, 1e300, 1.0), "quantiser cell of zero width");
}

TEST(TruncatedMoments, FilterReportsAReadingWithoutMassAsANumericalFailureAndKeepsItsState) {
  // The route of the fuzz finding: LcGaussianFilter::Correct → ThresholdSensor::Tilt →
  // StandardTruncatedMoments(0, 0). Now the step is refused through the status, state bit-identical.
  LcGaussianFilter filter(Eigen::VectorXd::Constant(1, 0.0), Eigen::MatrixXd::Constant(1, 1, 1e300));
  const Eigen::VectorXd m0 = filter.mean();
  const Eigen::MatrixXd p0 = filter.covariance();
  const double ll0 = filter.log_likelihood();
  ThresholdSensor sensor(kC, 1e-200);
  const StepReport r = filter.Correct(sensor, 0.0);
  EXPECT_EQ(r.status, StepStatus::kNumericalFailure);
  EXPECT_TRUE(filter.mean() == m0 && filter.covariance() == p0 && filter.log_likelihood() == ll0);
  // A reading with mass is then taken as usual: N(0, 1e300) given |s| < 1 has mean 0 (by symmetry).
  // (Its variance 1/3 is lost in P − (σ² − v_s) = 1e300 − (1e300 − 1/3): not asserted here.)
  ThresholdSensor unit(kC, 1.0);
  ASSERT_TRUE(filter.Correct(unit, 0.0).updated());
  EXPECT_NEAR(filter.mean()(0), 0.0, 1e-12);
  EXPECT_GE(filter.covariance()(0, 0), 0.0);
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
        z += w;
        s1 += w * t;
        s2 += w * t * t;
      }
      const double var = s2 / z - (s1 / z) * (s1 / z);
      EXPECT_LE(var, 1.0 / (8 * n * std::log(2.0)) * (1 + 1e-6)) << "trial " << trial << " n " << n;
    }
  }
}

}  // namespace
}  // namespace ident::models
