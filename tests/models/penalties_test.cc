// Convex penalties (models/penalties.h): closed-form values against their textbook formulas and the
// PLQ sup-representation evaluated by brute force; conjugates against a brute-force sup over a fine
// grid; Fenchel-Young equality at the conjugate's gradient; bad parameters rejected.
#include "models/penalties.h"

#include <cmath>
#include <random>

#include <gtest/gtest.h>
#include <Eigen/LU>

#include "common/error.h"

namespace ident::models {
namespace {

std::vector<Penalty> ScalarPenalties() {
  Eigen::VectorXd knots(5), values(5);
  knots << -2, -0.5, 0.2, 1, 3;
  values << 3, 0.5, 0.1, 0.4, 2.5;  // slopes -5/3, -4/7, 3/8, 21/20: convex
  return {Penalty::Quadratic(Eigen::MatrixXd::Constant(1, 1, 2.5)),
          Penalty::L1(),
          Penalty::Huber(0.7),
          Penalty::Vapnik(0.4),
          Penalty::Quantile(0.3),
          Penalty::BoxMonitoring(Eigen::VectorXd::Constant(1, -0.5), Eigen::VectorXd::Constant(1, 2.0),
                                 Eigen::MatrixXd::Constant(1, 1, 0.8)),
          Penalty::PiecewiseLinear(knots, values)};
}

Eigen::VectorXd V1(double x) { return Eigen::VectorXd::Constant(1, x); }

// Maximum of a concave function on [a, b] by ternary search (independent numerical optimisation).
template <class Fn>
double MaximiseConcave(Fn fn, double a, double b) {
  for (int i = 0; i < 300; ++i) {
    const double m1 = a + (b - a) / 3, m2 = b - (b - a) / 3;
    if (fn(m1) < fn(m2))
      a = m1;
    else
      b = m2;
  }
  return fn(0.5 * (a + b));
}

// rho(r) = p'r + p0 + sup_{lo<=u<=hi} { u'(B r - b) - 1/2 u'M u } by maximising over each u coordinate
// (independent when M is diagonal, which holds for every scalar penalty here).
double PlqBySearch(const PlqForm& f, double r) {
  double sum = f.p(0) * r + f.p0;
  for (int i = 0; i < f.rows(); ++i) {
    const double a = f.B(i, 0) * r - f.b(i), m = f.M(i, i);
    const double lo = std::isfinite(f.lo(i)) ? f.lo(i) : -1e3, hi = std::isfinite(f.hi(i)) ? f.hi(i) : 1e3;
    sum += MaximiseConcave([&](double u) { return u * a - 0.5 * m * u * u; }, lo, hi);
  }
  return sum;
}

TEST(Penalties, ClosedFormValuesMatchTheirFormulas) {
  EXPECT_DOUBLE_EQ(Penalty::Quadratic(Eigen::MatrixXd::Constant(1, 1, 4.0)).Value(V1(3)), 0.5 * 9 / 4);
  EXPECT_DOUBLE_EQ(Penalty::L1().Value(V1(-2.5)), 2.5);
  EXPECT_DOUBLE_EQ(Penalty::Huber(1.5).Value(V1(3)), 1.5 * 3 - 0.5 * 1.5 * 1.5);
  EXPECT_DOUBLE_EQ(Penalty::Huber(1.5).Value(V1(-1)), 0.5);
  EXPECT_DOUBLE_EQ(Penalty::Vapnik(0.5).Value(V1(-2)), 1.5);
  EXPECT_DOUBLE_EQ(Penalty::Vapnik(0.5).Value(V1(0.3)), 0.0);
  EXPECT_DOUBLE_EQ(Penalty::Quantile(0.3).Value(V1(2)), 0.6);
  EXPECT_DOUBLE_EQ(Penalty::Quantile(0.3).Value(V1(-2)), 1.4);
  Eigen::MatrixXd C(2, 2);
  C << 2, 0.5, 0.5, 1;
  Eigen::VectorXd r(2);
  r << 1, -2;
  EXPECT_NEAR(Penalty::Quadratic(C).Value(r), 0.5 * r.dot(C.inverse() * r), 1e-14);
  EXPECT_DOUBLE_EQ(Penalty::L1(2).Value(r), 3.0);
}

TEST(Penalties, ValueEqualsItsPlqSupRepresentationByNumericalMaximisation) {
  for (const Penalty& f : ScalarPenalties())
    for (double r : {-1.7, -0.6, -0.1, 0.0, 0.25, 0.9, 2.2}) {
      const double value = f.Value(V1(r));
      EXPECT_NEAR(PlqBySearch(f.plq(), r), value, 1e-9 * (1 + std::abs(value))) << f.Name() << " r = " << r;
    }
}

TEST(Penalties, PiecewiseLinearIsInfiniteOutsideItsKnots) {
  const Penalty f = ScalarPenalties().back();
  EXPECT_EQ(f.Value(V1(-2.001)), kInfinity);
  EXPECT_EQ(f.Value(V1(3.001)), kInfinity);
  EXPECT_DOUBLE_EQ(f.Value(V1(3.0 + 1e-12), 1e-9), 2.5);
  EXPECT_DOUBLE_EQ(f.Value(V1(0.6)), 0.1 + 0.4 * 0.3 / 0.8);
}

// The same penalty in units s times smaller (knots × s, values × s²) has the same kinks: the PLQ form keeps
// one row per kink plus the two domain bounds, and its value is s² times the original at r/s.
TEST(Penalties, PiecewiseLinearKeepsItsKinksInAnyUnit) {
  const Penalty f = ScalarPenalties().back();
  for (const double s : {0x1p-40, 1e-6, 1.0, 1e6}) {
    const Penalty g = Penalty::PiecewiseLinear(s * f.knots(), s * s * f.values());
    EXPECT_EQ(g.plq().rows(), f.plq().rows()) << "s " << s;
    for (const double r : {-1.7, -0.4, 0.2, 0.6, 2.9})
      EXPECT_NEAR(g.Value(V1(s * r)), s * s * f.Value(V1(r)), 1e-12 * s * s * (1 + std::abs(f.Value(V1(r)))))
          << "s " << s << " r " << r;
  }
}

// rho*(v) = sup_r { v r - rho(r) } over r in [-40, 40] (or dom rho) by ternary search on the concave
// function; +inf is recognised when the sup keeps growing towards the ends of [-40, 40].
double ConjugateBySearch(const Penalty& f, double v) {
  double a = -40, b = 40;
  if (f.kind() == Penalty::Kind::kPiecewiseLinear) {
    a = f.knots()(0);
    b = f.knots()(f.knots().size() - 1);
  }
  return MaximiseConcave([&](double r) { return v * r - f.Value(V1(r)); }, a, b);
}

TEST(Penalties, ConjugateEqualsTheSupFoundByNumericalMaximisation) {
  for (const Penalty& f : ScalarPenalties())
    for (double v : {-1.2, -0.9, -0.35, 0.0, 0.2, 0.29, 0.6, 0.95, 1.3, 1.9}) {
      const double conj = f.Conjugate(V1(v));
      const double grid = ConjugateBySearch(f, v);
      if (std::isinf(conj)) {
        EXPECT_GT(grid, 4.0) << f.Name() << " v = " << v << ": outside dom rho* the sup grows without bound";
      } else {
        EXPECT_NEAR(grid, conj, 1e-9 * (1 + std::abs(conj))) << f.Name() << " v = " << v;
      }
    }
}

TEST(Penalties, FenchelYoungHoldsWithEqualityAtTheConjugateGradient) {
  // r in d rho*(v)  <=>  rho(r) + rho*(v) = v r.
  for (const Penalty& f : ScalarPenalties())
    for (double v : {-0.45, 0.05, 0.25, 0.9}) {
      if (std::isinf(f.Conjugate(V1(v)))) continue;
      const Eigen::VectorXd r = f.ConjugateGradient(V1(v));
      EXPECT_NEAR(f.Value(r) + f.Conjugate(V1(v)), v * r(0), 1e-12) << f.Name() << " v = " << v;
    }
}

TEST(Penalties, ConjugateIsDifferentiableExactlyWhereTheSupHasOneMaximiser) {
  // d rho*(v) = argmax_r {v r - rho(r)}: found on a grid (r in [-10, 10], step 2e-3) as the set within
  // 1e-9 of the max. A single maximiser (width <= 2 grid steps: r* may fall half-way between two grid
  // points) means rho* is differentiable at v; a
  // segment or a ray (width > 0.1) means it is not. v runs over a grid (step 0.05) plus every kink of
  // the conjugates: +-1 (l1), +-0.7 (Huber), 0 and +-1 (Vapnik), -0.7 and 0.3 (quantile), -0.5 and 2
  // (box), and the piecewise-linear slopes -5/3, -4/7, 3/8, 21/20.
  std::vector<double> vs = {1.0, -1.0, 0.7, -0.7, 0.0, 0.3, -0.5, 2.0, -5.0 / 3, -4.0 / 7, 3.0 / 8, 21.0 / 20};
  for (int i = 0; i <= 90; ++i) vs.push_back(-2.2 + 0.05 * i);
  int unique = 0, not_unique = 0;
  for (const Penalty& f : ScalarPenalties())
    for (double v : vs) {
      if (std::isinf(f.Conjugate(V1(v)))) continue;
      double best = -kInfinity;
      for (int i = 0; i <= 10000; ++i) {
        const double r = -10 + 2e-3 * i;
        best = std::max(best, v * r - f.Value(V1(r)));
      }
      double lo = kInfinity, hi = -kInfinity;
      for (int i = 0; i <= 10000; ++i) {
        const double r = -10 + 2e-3 * i;
        if (v * r - f.Value(V1(r)) >= best - 1e-9 * (1 + std::abs(best))) {
          lo = std::min(lo, r);
          hi = std::max(hi, r);
        }
      }
      const double width = hi - lo;
      const bool single = width < 4.1e-3;
      ASSERT_TRUE(single || width > 0.1) << f.Name() << " v = " << v << ": width " << width;
      EXPECT_EQ(f.ConjugateIsDifferentiableNear(V1(v), 1e-4), single) << f.Name() << " v = " << v;
      (single ? unique : not_unique)++;
    }
  EXPECT_GT(unique, 200);
  EXPECT_GT(not_unique, 20);
}

TEST(Penalties, NonDiagonalBoxMonitoringMatchesTheMultivariateSup) {
  Eigen::MatrixXd M(2, 2);
  M << 1.0, 0.6, 0.6, 0.5;
  Eigen::VectorXd lo(2), hi(2), r(2);
  lo << -1, -0.5;
  hi << 1, 2;
  const Penalty f = Penalty::BoxMonitoring(lo, hi, M);
  std::mt19937 rng(3);
  std::normal_distribution<double> N(0, 2);
  for (int trial = 0; trial < 5; ++trial) {
    r << N(rng), N(rng);
    double best = -kInfinity;
    for (int i = 0; i <= 800; ++i)
      for (int j = 0; j <= 800; ++j) {
        Eigen::Vector2d u(lo(0) + (hi(0) - lo(0)) * i / 800.0, lo(1) + (hi(1) - lo(1)) * j / 800.0);
        best = std::max(best, r.dot(u) - 0.5 * u.dot(M * u));
      }
    EXPECT_NEAR(f.Value(r), best, 2e-4) << r.transpose();
    EXPECT_GE(f.Value(r), best - 1e-12);  // the grid sup is a lower bound
  }
  Eigen::VectorXd v(2);
  v << 0.5, 1.5;
  EXPECT_DOUBLE_EQ(f.Conjugate(v), 0.5 * v.dot(M * v));  // Lemma 2.8
  v << 1.5, 0;
  EXPECT_EQ(f.Conjugate(v), kInfinity);
}

TEST(Penalties, BadParametersAreRejectedWithTheParameterNamed) {
  auto message = [](auto make) {
    try {
      make();
    } catch (const InvalidArgument& e) {
      return std::string(e.what());
    }
    return std::string("no exception");
  };
  EXPECT_NE(message([] { Penalty::Huber(0); }).find("kappa"), std::string::npos);
  EXPECT_NE(message([] { Penalty::Vapnik(-1); }).find("epsilon"), std::string::npos);
  EXPECT_NE(message([] { Penalty::Quantile(1.0); }).find("tau"), std::string::npos);
  EXPECT_NE(message([] { Penalty::Quadratic(-Eigen::MatrixXd::Identity(2, 2)); }).find("positive definite"),
            std::string::npos);
  Eigen::VectorXd k(3), v(3);
  k << 0, 1, 2;
  v << 0, 1, 0;  // concave
  EXPECT_NE(message([&] { Penalty::PiecewiseLinear(k, v); }).find("not convex"), std::string::npos);
  k << 0, 2, 1;
  EXPECT_NE(message([&] { Penalty::PiecewiseLinear(k, v); }).find("increase"), std::string::npos);
  EXPECT_NE(message([] { Penalty::L1().Value(Eigen::VectorXd::Zero(2)); }).find("dimension"), std::string::npos);
}

}  // namespace
}  // namespace ident::models
