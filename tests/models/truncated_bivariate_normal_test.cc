// Tallis' moments of a bivariate normal on a quadrant (models/truncated_bivariate_normal.h) against
// independent references: nested 2-D adaptive quadrature of the density (1e-10), Owen's T closed form of
// the bivariate normal CDF (Boost.Math), the 1-D truncated normal when one side is unbounded, and the
// product of 1-D truncations when ρ = 0. Then the crossing update of the log-concave Gaussian filter
// (studies/mems/crossing_reading.h) against 2-D quadrature of the posterior of x(k) written the other way round.
#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

#include <gtest/gtest.h>
#include <boost/math/distributions/normal.hpp>
#include <boost/math/quadrature/gauss_kronrod.hpp>
#include <boost/math/special_functions/owens_t.hpp>

#include "ident/observers/lc_gaussian_filter.h"
#include "models/measurement.h"
#include "models/state_space.h"
#include "models/truncated_bivariate_normal.h"
#include "studies/mems/crossing_reading.h"
#include "tests/support/sanitizer.h"

namespace ident::models {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
using GK = boost::math::quadrature::gauss_kronrod<double, 61>;

// Adaptive GK over [a, b] with extra cut points (only those strictly inside are used).
template <class F>
double Integrate(F f, double a, double b, std::vector<double> cuts = {}) {
  if (!(b > a)) return 0.0;
  std::vector<double> pts{a};
  for (double c : cuts)
    if (c > a && c < b) pts.push_back(c);
  pts.push_back(b);
  std::sort(pts.begin(), pts.end());
  double sum = 0;
  for (size_t i = 0; i + 1 < pts.size(); ++i) {  // mapped onto [−1, 1] (Boost compares an unscaled error)
    const double half = 0.5 * (pts[i + 1] - pts[i]), mid = 0.5 * (pts[i + 1] + pts[i]);
    sum += half * GK::integrate([&](double t) { return f(mid + half * t); }, -1.0, 1.0, 12, 1e-13);
  }
  return sum;
}

struct Reference {
  double log_probability;
  Eigen::Vector2d mean;
  Eigen::Matrix2d covariance;
};

// Nested 2-D quadrature of N(s; μ, Σ) 1{side_i (s_i − b_i) > 0}: outer over s1 (marginal density), inner
// over s2 | s1 ~ N(μc(s1), σc²) on its ±12 σc window clipped to the region (outside: below e^(−72)). Moments are
// central (two passes).
Reference QuadratureMoments(const Eigen::Vector2d& mu, const Eigen::Matrix2d& S, const Eigen::Vector2d& b,
                            const Eigen::Vector2d& side) {
  const double s1 = std::sqrt(S(0, 0)), beta = S(0, 1) / S(0, 0);
  const double sc = std::sqrt(S(1, 1) - S(0, 1) * S(0, 1) / S(0, 0));
  // Range of s1: the region's side of b1, within 12 sd of max/min(μ1, b1).
  double lo1 = mu(0) - 12 * s1, hi1 = mu(0) + 12 * s1;
  if (side(0) > 0)
    lo1 = std::max(lo1, b(0)), hi1 = std::max(hi1, b(0) + 12 * s1);
  else
    hi1 = std::min(hi1, b(0)), lo1 = std::min(lo1, b(0) - 12 * s1);
  auto inner = [&](double x1, auto g) {  // ∫ g(x2) N(x2; μc, σc²) over the region's side of b2
    const double mc = mu(1) + beta * (x1 - mu(0));
    double lo = mc - 12 * sc, hi = mc + 12 * sc;
    if (side(1) > 0)
      lo = std::max(lo, b(1));
    else
      hi = std::min(hi, b(1));
    return Integrate(
        [&](double x2) {
          return g(x2) * std::exp(-0.5 * (x2 - mc) * (x2 - mc) / (sc * sc)) / (sc * std::sqrt(2 * std::numbers::pi));
        },
        lo, hi, {mc});
  };
  auto marginal = [&](double x1) {
    return std::exp(-0.5 * (x1 - mu(0)) * (x1 - mu(0)) / S(0, 0)) / (s1 * std::sqrt(2 * std::numbers::pi));
  };
  // Cut where μc(s1) = b2 (the inner mass switches on over a width σc/|β|) and at μ1.
  std::vector<double> cuts{mu(0)};
  if (beta != 0) cuts.push_back(mu(0) + (b(1) - mu(1)) / beta);
  auto outer = [&](auto g) {
    return Integrate([&](double x1) { return marginal(x1) * inner(x1, [&](double x2) { return g(x1, x2); }); }, lo1,
                     hi1, cuts);
  };
  const double z = outer([](double, double) { return 1.0; });
  const double m1 = outer([](double x1, double) { return x1; }) / z;
  const double m2 = outer([](double, double x2) { return x2; }) / z;
  Reference r;
  r.log_probability = std::log(z);
  r.mean << m1, m2;
  r.covariance(0, 0) = outer([&](double x1, double) { return (x1 - m1) * (x1 - m1); }) / z;
  r.covariance(1, 1) = outer([&](double, double x2) { return (x2 - m2) * (x2 - m2); }) / z;
  r.covariance(0, 1) = r.covariance(1, 0) = outer([&](double x1, double x2) { return (x1 - m1) * (x2 - m2); }) / z;
  return r;
}

Eigen::Matrix2d Cov(double v1, double v2, double rho) {
  Eigen::Matrix2d S;
  S << v1, rho * std::sqrt(v1 * v2), rho * std::sqrt(v1 * v2), v2;
  return S;
}

struct Case {
  Eigen::Vector2d mu;
  Eigen::Matrix2d S;
  Eigen::Vector2d b, side;
};

TEST(TruncatedBivariateNormal, TallisMomentsEqualTwoDimensionalQuadratureTo1e10) {
  std::vector<Case> cases;
  // A grid of correlations, bounds on both sides of the mean, all four quadrant orientations.
  // Under the sanitizer every 5th of these 24 (tests/support/sanitizer.h): every correlation, b1 and orientation.
  int grid_case = 0;
  for (double rho : {-0.9, 0.0, 0.95})
    for (double b1 : {-1.5, 2.0})
      for (int o = 0; o < 4; ++o) {
        const double b2 = o < 2 ? -0.7 : 1.1;
        if (ident::testing::RunsCase(grid_case++, 5))
          cases.push_back({Eigen::Vector2d(0.3, -0.2), Cov(0.8, 2.5, rho), Eigen::Vector2d(b1, b2),
                           Eigen::Vector2d(o & 1 ? -1 : 1, o & 2 ? -1 : 1)});
      }
  // MEMS crossing 0 → +1: s1 = x1(k−1) < 1 ≤ s2 = x1(k), ρ ≈ 0.998; and the way back, +1 → 0.
  cases.push_back(
      {Eigen::Vector2d(0.97, 1.0), Cov(0.004, 0.0041, 0.998), Eigen::Vector2d(1, 1), Eigen::Vector2d(-1, 1)});
  cases.push_back(
      {Eigen::Vector2d(1.02, 0.99), Cov(0.001, 0.0012, 0.9995), Eigen::Vector2d(1, 1), Eigen::Vector2d(1, -1)});
  // Tails: the quadrant is 5-7 sd away (probability ~1e-7 … 1e-12).
  cases.push_back({Eigen::Vector2d(0, 0), Cov(1, 1, 0.6), Eigen::Vector2d(5, 5.5), Eigen::Vector2d(1, 1)});
  cases.push_back({Eigen::Vector2d(0, 0), Cov(1, 4, -0.4), Eigen::Vector2d(4, -7), Eigen::Vector2d(1, -1)});
  for (const Case& c : cases) {
    const auto t = TruncatedBivariateNormalMoments(c.mu, c.S, c.b, c.side);
    const Reference r = QuadratureMoments(c.mu, c.S, c.b, c.side);
    const std::string where = ::testing::PrintToString(c.b.transpose()) + " sides " +
                              ::testing::PrintToString(c.side.transpose()) + " S " + ::testing::PrintToString(c.S);
    ASSERT_TRUE(t.ok) << where;
    EXPECT_NEAR(t.log_probability, r.log_probability, 1e-10 * std::max(1.0, std::abs(r.log_probability))) << where;
    for (int i = 0; i < 2; ++i) {
      EXPECT_NEAR(t.mean(i), r.mean(i), 1e-10 * std::sqrt(c.S(i, i))) << where;
      for (int j = 0; j < 2; ++j)
        EXPECT_NEAR(t.covariance(i, j), r.covariance(i, j), 1e-10 * std::sqrt(c.S(i, i) * c.S(j, j))) << where;
    }
    // Truncation to a log-concave region shrinks the covariance: S − V ≥ 0 (Brascamp–Lieb, [1, Thm 2]).
    const Eigen::Matrix2d d = c.S - t.covariance;
    EXPECT_GE(d(0, 0), 0);
    EXPECT_GE(d.determinant(), -1e-12 * c.S.determinant());
  }
}

// Φ2(h, k; ρ) = P(X ≤ h, Y ≤ k) by Owen's T (Owen 1956): ½Φ(h) + ½Φ(k) − T(h, a_h) − T(k, a_k) − β.
double OwenBivariateCdf(double h, double k, double rho) {
  const boost::math::normal n;
  const double s = std::sqrt(1 - rho * rho);
  const double ah = (k - rho * h) / (h * s), ak = (h - rho * k) / (k * s);
  const double beta = (h * k > 0 || (h * k == 0 && h + k >= 0)) ? 0.0 : 0.5;
  return 0.5 * boost::math::cdf(n, h) + 0.5 * boost::math::cdf(n, k) - boost::math::owens_t(h, ah) -
         boost::math::owens_t(k, ak) - beta;
}

TEST(TruncatedBivariateNormal, OrthantProbabilityEqualsOwensTClosedForm) {
  for (double rho : {-0.99, -0.5, 0.0, 0.3, 0.9, 0.999})
    for (double h : {-2.5, -0.4, 0.7, 1.9})
      for (double k : {-1.2, 0.35, 2.2}) {
        const double owen = OwenBivariateCdf(-h, -k, rho);  // P(X > h, Y > k) = Φ2(−h, −k; ρ)
        EXPECT_NEAR(std::exp(LogUpperOrthantProbability(h, k, rho)), owen, 1e-12) << h << " " << k << " " << rho;
      }
}

TEST(TruncatedBivariateNormal, OwensTBranchEqualsTheAdaptiveQuadratureTo1e10) {
  // The closed form (used when P ≥ 1e-5) against the adaptive quadrature it replaced, relative 1e-10,
  // including MEMS-like crossing wedges (ρ = −0.9995, bounds a fraction of an sd apart) and values near
  // the switch to the quadrature branch.
  int closed_form = 0;
  for (double rho : {-0.9995, -0.99, -0.5, 0.0, 0.3, 0.9, 0.998, 0.9995})
    for (double h : {-3.1, -2.5, -0.4, -0.02, 0.01, 0.7, 1.9, 3.3})
      for (double k : {-2.9, -1.2, -0.03, 0.02, 0.35, 2.2, 3.6}) {
        const double quad = LogUpperOrthantProbabilityByQuadrature(h, k, rho);
        const double log_p = LogUpperOrthantProbability(h, k, rho);
        if (!std::isfinite(quad)) {
          EXPECT_FALSE(log_p > quad) << h << " " << k << " " << rho;
          continue;
        }
        EXPECT_NEAR(log_p, quad, 1e-10) << h << " " << k << " " << rho;
        if (quad >= std::log(1e-5)) ++closed_form;
      }
  EXPECT_GT(closed_form, 200);  // most cases exercise the closed form
}

TEST(TruncatedBivariateNormal, OneUnboundedSideIsTheOneDimensionalTruncationAndItsRegression) {
  const Eigen::Vector2d mu(0.4, -1.0);
  const Eigen::Matrix2d S = Cov(0.5, 2.0, 0.7);
  for (double side : {-1.0, 1.0}) {
    const auto t = TruncatedBivariateNormalMoments(mu, S, Eigen::Vector2d(0.9, -kInf), Eigen::Vector2d(side, 1));
    const auto one = TruncatedNormalMoments(mu(0), S(0, 0), side > 0 ? 0.9 : -kInf, side > 0 ? kInf : 0.9);
    ASSERT_TRUE(t.ok && one.ok);
    EXPECT_NEAR(t.log_probability, one.log_normalizer, 1e-13);
    EXPECT_NEAR(t.mean(0), one.mean, 1e-13);
    EXPECT_NEAR(t.covariance(0, 0), one.variance, 1e-13);
    // s2 = μ2 + β (s1 − μ1) + e, e independent of s1: E and Var follow by regression.
    const double beta = S(0, 1) / S(0, 0), ve = S(1, 1) - beta * S(0, 1);
    EXPECT_NEAR(t.mean(1), mu(1) + beta * (one.mean - mu(0)), 1e-12);
    EXPECT_NEAR(t.covariance(0, 1), beta * one.variance, 1e-12);
    EXPECT_NEAR(t.covariance(1, 1), ve + beta * beta * one.variance, 1e-12);
  }
}

TEST(TruncatedBivariateNormal, IndependentPairIsTheProductOfOneDimensionalTruncations) {
  const Eigen::Vector2d mu(1.0, 2.0);
  const auto t =
      TruncatedBivariateNormalMoments(mu, Cov(2.0, 0.3, 0.0), Eigen::Vector2d(1.5, 1.8), Eigen::Vector2d(1, -1));
  const auto a = TruncatedNormalMoments(1.0, 2.0, 1.5, kInf), b = TruncatedNormalMoments(2.0, 0.3, -kInf, 1.8);
  ASSERT_TRUE(t.ok);
  EXPECT_NEAR(t.log_probability, a.log_normalizer + b.log_normalizer, 1e-13);
  EXPECT_NEAR(t.mean(0), a.mean, 1e-13);
  EXPECT_NEAR(t.mean(1), b.mean, 1e-13);
  EXPECT_NEAR(t.covariance(0, 0), a.variance, 1e-13);
  EXPECT_NEAR(t.covariance(1, 1), b.variance, 1e-13);
  EXPECT_NEAR(t.covariance(0, 1), 0.0, 1e-14);
}

TEST(TruncatedBivariateNormal, InvalidInputOrNoMassIsNotOk) {
  const Eigen::Vector2d mu(0, 0), b(0, 0), side(1, 1);
  const Eigen::Matrix2d S = Cov(1, 1, 0.5);
  EXPECT_FALSE(TruncatedBivariateNormalMoments(mu, Cov(1, 1, 1.0), b, side).ok);  // singular
  EXPECT_FALSE(TruncatedBivariateNormalMoments(Eigen::Vector2d(NAN, 0), S, b, side).ok);
  EXPECT_FALSE(TruncatedBivariateNormalMoments(mu, S, Eigen::Vector2d(NAN, 0), side).ok);
  EXPECT_FALSE(TruncatedBivariateNormalMoments(mu, S, b, Eigen::Vector2d(0.5, 1)).ok);      // side not ±1
  EXPECT_FALSE(TruncatedBivariateNormalMoments(mu, S, Eigen::Vector2d(kInf, 0), side).ok);  // empty
  EXPECT_FALSE(TruncatedBivariateNormalMoments(mu, Cov(-1, 1, 0), b, side).ok);
  EXPECT_FALSE(TruncatedBivariateNormalMoments(mu, S, Eigen::Vector2d(60, 60), side).ok);  // e^(−1800)
  EXPECT_TRUE(std::isnan(LogUpperOrthantProbability(0, 0, 1.0)));
  EXPECT_EQ(LogUpperOrthantProbability(kInf, 0, 0.2), -kInf);
}

TEST(TruncatedBivariateNormal, ThresholdChangeRegions) {
  // (y_prev, y) → quadrant of (x1(k−1), x1(k)), threshold 1.
  struct Row {
    double y_prev, y, b1, b2, s1, s2;
  };
  for (const Row& r : {Row{0, 1, 1, 1, -1, 1}, Row{0, -1, -1, -1, 1, -1}, Row{1, 0, 1, 1, 1, -1},
                       Row{-1, 0, -1, -1, -1, 1}, Row{-1, 1, -1, 1, -1, 1}, Row{1, -1, 1, -1, 1, -1}}) {
    const auto q = ThresholdChangeRegion(1.0, r.y_prev, r.y);
    ASSERT_TRUE(q.ok);
    EXPECT_EQ(q.bounds, Eigen::Vector2d(r.b1, r.b2)) << r.y_prev << " → " << r.y;
    EXPECT_EQ(q.sides, Eigen::Vector2d(r.s1, r.s2)) << r.y_prev << " → " << r.y;
  }
  EXPECT_FALSE(ThresholdChangeRegion(1.0, 0, 0).ok);
  EXPECT_FALSE(ThresholdChangeRegion(1.0, 1, 1).ok);
  EXPECT_FALSE(ThresholdChangeRegion(1.0, 0, 0.5).ok);
}

// The crossing update of x(k) against the posterior written the other way round: p(x(k) | wedge) ∝
// N(x(k); m, P) · 1{x1(k) ≥ T} · P(x1(k−1) < T | x(k)), with x1(k−1) | x(k) Gaussian (backward regression),
// integrated over x(k) by nested quadrature (outer x1, inner x2 given x1).
TEST(CrossingReading, UpdateEqualsQuadratureOfTheBackwardFormTo1e9) {
  const double h = 0.01, T = 1.0;
  const auto model = MemsAccelerometerDynamics(h, 1.0);
  Eigen::Vector2d m_before(0.95, 3.0);
  Eigen::Matrix2d P_before;
  P_before << 0.002, 0.01, 0.01, 0.3;
  // Under the sanitizer the braking case only (tests/support/sanitizer.h).
  const double inputs[] = {-40.0, 0.0};
  for (int c = 0; c < 2; ++c) {
    if (!ident::testing::RunsCase(c, 2)) continue;
    const double u = inputs[c];
    BasicLcGaussianFilter<2> f(m_before, P_before);
    f.Predict(model, Eigen::VectorXd::Constant(1, u));
    const Eigen::Vector2d m = f.mean();
    const Eigen::Matrix2d P = f.covariance();
    const StepReport rep =
        ident::CorrectReadingChange(f, m_before, P_before, model, ThresholdSensor(Eigen::Vector2d(1, 0), T), 0.0, 1.0);
    ASSERT_TRUE(rep.updated());
    // Joint of (x(k), x1(k−1)): Cov(x(k), x1(k−1)) = A P⁻ e1.
    const Eigen::Vector2d cross = model.A * P_before.col(0);
    const Eigen::Vector2d g = P.inverse() * cross;    // E[x1(k−1) | x] = m⁻1 + g'(x − m)
    const double vb = P_before(0, 0) - cross.dot(g);  // Var[x1(k−1) | x(k)]
    const boost::math::normal n;
    const Eigen::Matrix2d Pi = P.inverse();
    auto w = [&](double x1, double x2) {
      const Eigen::Vector2d d(x1 - m(0), x2 - m(1));
      const double back_mean = m_before(0) + g.dot(d);
      return std::exp(-0.5 * d.dot(Pi * d)) * boost::math::cdf(n, (T - back_mean) / std::sqrt(vb));
    };
    // x2 | x1 under N(m, P): mean m2 + P21/P11 (x1 − m1), sd √(P22 − P21²/P11).
    const double sc = std::sqrt(P(1, 1) - P(0, 1) * P(0, 1) / P(0, 0));
    auto outer = [&](auto fn) {
      return Integrate(
          [&](double x1) {
            const double mc = m(1) + P(0, 1) / P(0, 0) * (x1 - m(0));
            return Integrate([&](double x2) { return fn(x1, x2) * w(x1, x2); }, mc - 12 * sc, mc + 12 * sc, {mc});
          },
          T, T + 12 * std::sqrt(P(0, 0)));
    };
    const double z = outer([](double, double) { return 1.0; });
    const double e1 = outer([](double x1, double) { return x1; }) / z;
    const double e2 = outer([](double, double x2) { return x2; }) / z;
    const double v11 = outer([&](double x1, double) { return (x1 - e1) * (x1 - e1); }) / z;
    const double v22 = outer([&](double, double x2) { return (x2 - e2) * (x2 - e2); }) / z;
    const double v12 = outer([&](double x1, double x2) { return (x1 - e1) * (x2 - e2); }) / z;
    EXPECT_NEAR(f.mean()(0), e1, 1e-9 * std::sqrt(P(0, 0))) << "u " << u;
    EXPECT_NEAR(f.mean()(1), e2, 1e-9 * std::sqrt(P(1, 1))) << "u " << u;
    EXPECT_NEAR(f.covariance()(0, 0), v11, 1e-9 * P(0, 0)) << "u " << u;
    EXPECT_NEAR(f.covariance()(1, 1), v22, 1e-9 * P(1, 1)) << "u " << u;
    EXPECT_NEAR(f.covariance()(0, 1), v12, 1e-9 * std::sqrt(P(0, 0) * P(1, 1))) << "u " << u;
    // The velocity is informed too: its variance drops below the prediction's.
    EXPECT_LT(f.covariance()(1, 1), 0.9 * P(1, 1));
  }
}

TEST(CrossingReading, RejectsSameReadingAndWrongSizesWithoutTouchingTheState) {
  const auto model = MemsAccelerometerDynamics(0.01, 1.0);
  BasicLcGaussianFilter<2> f(Eigen::Vector2d(0.9, 2.0), Eigen::Matrix2d::Identity() * 0.01);
  const Eigen::Vector2d m_before = f.mean();
  const Eigen::Matrix2d P_before = f.covariance();
  f.Predict(model, Eigen::VectorXd::Zero(1));
  const Eigen::Vector2d m = f.mean();
  const ThresholdSensor sensor(Eigen::Vector2d(1, 0), 1.0);
  EXPECT_EQ(ident::CorrectReadingChange(f, m_before, P_before, model, sensor, 0.0, 0.0).status,
            StepStatus::kRejectedInvalid);
  EXPECT_EQ(ident::CorrectReadingChange(f, Eigen::Vector3d::Zero(), P_before, model, sensor, 0.0, 1.0).status,
            StepStatus::kRejectedInvalid);
  // Wedge with no mass: the mass is 60 sd inside, so crossing in one step is impossible to double precision.
  BasicLcGaussianFilter<2> g(Eigen::Vector2d(-0.2, 0.0), Eigen::Matrix2d::Identity() * 1e-4);
  const Eigen::Vector2d gm_before = g.mean();
  const Eigen::Matrix2d gP_before = g.covariance();
  g.Predict(model, Eigen::VectorXd::Zero(1));
  const Eigen::Vector2d gm = g.mean();
  EXPECT_EQ(ident::CorrectReadingChange(g, gm_before, gP_before, model, sensor, 0.0, 1.0).status,
            StepStatus::kNumericalFailure);
  EXPECT_EQ(g.mean(), gm);
  EXPECT_EQ(f.mean(), m);
}

}  // namespace
}  // namespace ident::models
