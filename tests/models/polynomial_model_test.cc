#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Core>

#include "common/error.h"
#include "models/polynomial_structure.h"
#include "models/pseudo_linear_regressor.h"
#include "tests/support/reference_linear_algebra.h"

namespace ident::models {
namespace {

TEST(PolynomialStructure, NamesOrdersAndParameters) {
  const auto armax = PolynomialStructure::Armax(2, {2}, 2, {3});
  EXPECT_EQ(armax.ToString(), "ARMAX(2,2,2,3)");
  EXPECT_EQ(armax.num_parameters(), 6);
  EXPECT_EQ(armax.first_regression_index(), 4);  // max(2, 3 + 2 − 1, nc = 2)
  EXPECT_EQ(armax.ParameterNames(), (std::vector<std::string>{"a1", "a2", "b1", "b2", "c1", "c2"}));
  const auto oe = PolynomialStructure::OutputError(2, 3, 1);
  EXPECT_EQ(oe.ToString(), "OE(2,3,1)");
  EXPECT_EQ(oe.first_regression_index(), 3);
  EXPECT_EQ(oe.ParameterNames(), (std::vector<std::string>{"b1", "b2", "f1", "f2", "f3"}));
  const auto bj = PolynomialStructure::BoxJenkins(2, 1, 1, 2, 1);
  EXPECT_EQ(bj.ToString(), "BJ(2,1,1,2,1)");
  EXPECT_EQ(bj.ParameterNames(), (std::vector<std::string>{"b1", "b2", "c1", "d1", "f1", "f2"}));
  EXPECT_EQ(bj.c_offset(), 2);
  EXPECT_EQ(bj.d_offset(), 3);
  EXPECT_EQ(bj.f_offset(), 4);
  EXPECT_EQ(PolynomialStructure::Armax(1, {1, 2}, 1, {0, 1}).ToString(), "ARMAX(1,[1,2],1,[0,1])");
}

TEST(PolynomialStructure, RejectsCombinationsThatAreNoneOfTheThree) {
  EXPECT_THROW(PolynomialStructure(2, {2}, {1}, 0, 0, 0), InvalidArgument);        // ARX
  EXPECT_THROW(PolynomialStructure(2, {2}, {1}, 0, 0, 2), InvalidArgument);        // A and F
  EXPECT_THROW(PolynomialStructure(2, {2}, {1}, 1, 1, 0), InvalidArgument);        // D without F
  EXPECT_THROW(PolynomialStructure(0, {2, 2}, {1, 1}, 0, 0, 1), InvalidArgument);  // F, two inputs
  EXPECT_THROW(PolynomialStructure(2, {2}, {1}, -1, 0, 0), InvalidArgument);
  EXPECT_THROW(PolynomialStructure(0, {0}, {1}, 0, 0, 1), InvalidArgument);  // OE without B
}

// The stability test against the roots of the companion matrix (Eigen's eigenvalues).
TEST(MonicStable, AgreesWithCompanionMatrixRoots) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> coefficient(-1.6, 1.6);
  int stable = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    const int n = 1 + trial % 5;
    std::vector<double> p(static_cast<std::size_t>(n)), work(static_cast<std::size_t>(n));
    for (double& c : p) c = coefficient(rng);
    const double radius = testing::CompanionRootModulus(p.data(), n);
    if (std::abs(radius - 1) < 1e-9) continue;  // on the circle: either answer is within rounding
    EXPECT_EQ(MonicStable(p.data(), n, work.data()), radius < 1) << "trial " << trial << " radius " << radius;
    stable += radius < 1;
  }
  EXPECT_GT(stable, 200);  // both answers are exercised
  EXPECT_TRUE(MonicStable(nullptr, 0, nullptr));
}

// The largest root modulus by bisection on the Schur–Cohn test against the companion matrix's eigenvalues, on
// random polynomials of orders 1 to 8 whose roots have moduli from 1e-3 to 1e3, and on ones with a root at 0.
TEST(LargestRootModulus, AgreesWithCompanionMatrixRoots) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> unit(-1, 1), exponent(-3, 3);
  double worst = 0;
  for (int trial = 0; trial < 1000; ++trial) {
    const int n = 1 + trial % 8;
    const double scale = std::pow(10.0, exponent(rng));
    std::vector<double> p(static_cast<std::size_t>(n));
    for (int j = 0; j < n; ++j) p[static_cast<std::size_t>(j)] = unit(rng) * std::pow(scale, j + 1);
    if (trial % 10 == 0) p.back() = 0;  // a root at 0
    const double reference = testing::CompanionRootModulus(p.data(), n);
    const double modulus = LargestRootModulus(p.data(), n);
    worst = std::max(worst, std::abs(modulus - reference) / reference);
    EXPECT_NEAR(modulus, reference, 1e-12 * reference)
        << "trial " << trial << " order " << n << " p "
        << Eigen::Map<const Eigen::VectorXd>(p.data(), n).transpose().format(Eigen::IOFormat(17));
  }
  std::printf("[ measured ] largest root modulus vs companion eigenvalues: worst relative difference %.3g\n", worst);
  const double zero[] = {0.0, 0.0}, nan[] = {0.5, std::nan("")};
  EXPECT_EQ(LargestRootModulus(zero, 2), 0.0);
  EXPECT_TRUE(std::isnan(LargestRootModulus(nan, 2)));
}

struct Record {
  std::vector<double> u, y;
};

// A(q) y = B(q) u(t − nk) + C(q) e and y = B/F u(t − nk) + e, simulated directly from the difference
// equations (zero initial conditions).
Record SimulateArmax(const std::vector<double>& a, const std::vector<double>& b, const std::vector<double>& c, int nk,
                     int n, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal;
  Record r{std::vector<double>(static_cast<std::size_t>(n)), std::vector<double>(static_cast<std::size_t>(n))};
  std::vector<double> e(static_cast<std::size_t>(n));
  for (int t = 0; t < n; ++t) {
    r.u[t] = normal(rng);
    e[t] = 0.3 * normal(rng);
    double y = e[t];
    for (std::size_t k = 1; k <= a.size(); ++k) y -= t >= int(k) ? a[k - 1] * r.y[t - k] : 0;
    for (std::size_t k = 0; k < b.size(); ++k) y += t - nk - int(k) >= 0 ? b[k] * r.u[t - nk - k] : 0;
    for (std::size_t k = 1; k <= c.size(); ++k) y += t >= int(k) ? c[k - 1] * e[t - k] : 0;
    r.y[t] = y;
  }
  return r;
}

// With a fixed θ, y − θ'φ(t) is the ARMAX prediction error computed from C ε = A y − B u (Ljung (4.20)),
// with ε = 0 before t0; pushing θ'φ instead of y simulates B/A u.
TEST(PseudoLinearRegressor, ArmaxPredictorAndSimulationMatchTheDifferenceEquations) {
  const std::vector<double> a{-1.5, 0.7}, b{1.0, 0.5}, c{-1.0, 0.2};
  const int nk = 1, n = 300;
  const Record r = SimulateArmax(a, b, c, nk, n, 3);
  const auto structure = PolynomialStructure::Armax(2, {2}, 2, {nk});
  Eigen::VectorXd theta(6);
  theta << -1.4, 0.6, 0.9, 0.4, -0.8, 0.1;  // not the true θ: any θ has its own predictor
  PseudoLinearRegressor reg(structure);
  reg.SetEstimate(theta);
  const int t0 = structure.first_regression_index();
  std::vector<double> eps(n, 0.0);
  Eigen::VectorXd z(6), u(1);
  for (int t = 0; t < n; ++t) {
    u(0) = r.u[t];
    const bool formed = reg.Next(u, z);
    EXPECT_EQ(formed, t >= t0);
    if (formed) {
      double e = r.y[t] + theta(0) * r.y[t - 1] + theta(1) * r.y[t - 2] - theta(2) * r.u[t - 1] - theta(3) * r.u[t - 2];
      e -= theta(4) * eps[t - 1] + theta(5) * eps[t - 2];
      eps[t] = e;
      EXPECT_NEAR(r.y[t] - theta.dot(z), e, 1e-12) << "t = " << t;
    }
    reg.PushOutput(r.y[t]);
  }
  // Simulation: the measured outputs before t0, then A y_s = B u.
  reg.Reset();
  std::vector<double> ys(n);
  for (int t = 0; t < n; ++t) {
    u(0) = r.u[t];
    if (reg.Next(u, z)) {
      ys[t] = theta.dot(z);
      const double direct =
          -theta(0) * ys[t - 1] - theta(1) * ys[t - 2] + theta(2) * r.u[t - 1] + theta(3) * r.u[t - 2];
      EXPECT_NEAR(ys[t], direct, 1e-12) << "t = " << t;
    } else {
      ys[t] = r.y[t];
    }
    reg.PushOutput(ys[t]);
  }
}

// OE: the one-step prediction is the noise-free output w = B/F u, whatever y is; BJ: the predictor
// ŷ = w + (1 − D/C)(y − w) (Ljung (4.37)), i.e. C ε = D (y − w).
TEST(PseudoLinearRegressor, OutputErrorAndBoxJenkinsPredictors) {
  const Record r = SimulateArmax({-1.5, 0.7}, {1.0, 0.5}, {}, 1, 200, 4);
  const auto bj = PolynomialStructure::BoxJenkins(2, 1, 1, 2, 1);
  Eigen::VectorXd theta(6);
  theta << 0.9, 0.4, 0.3, -0.5, -1.4, 0.6;  // b1 b2 c1 d1 f1 f2
  PseudoLinearRegressor reg(bj);
  reg.SetEstimate(theta);
  const int t0 = bj.first_regression_index();
  std::vector<double> w(200), eps(200, 0.0);
  Eigen::VectorXd z(6), u(1);
  for (int t = 0; t < 200; ++t) {
    u(0) = r.u[t];
    if (reg.Next(u, z)) {
      w[t] = theta(0) * r.u[t - 1] + theta(1) * r.u[t - 2] - theta(4) * w[t - 1] - theta(5) * w[t - 2];
      const double v = r.y[t] - w[t], v1 = r.y[t - 1] - w[t - 1];
      eps[t] = v + theta(3) * (t - 1 >= t0 ? v1 : 0.0) - theta(2) * eps[t - 1];
      EXPECT_NEAR(r.y[t] - theta.dot(z), eps[t], 1e-12) << "t = " << t;
    } else {
      w[t] = r.y[t];
    }
    reg.PushOutput(r.y[t]);
  }
  const auto oe = PolynomialStructure::OutputError(2, 2, 1);
  PseudoLinearRegressor oe_reg(oe);
  Eigen::VectorXd theta_oe(4);
  theta_oe << 0.9, 0.4, -1.4, 0.6;
  oe_reg.SetEstimate(theta_oe);
  Eigen::VectorXd z4(4);
  for (int t = 0; t < 200; ++t) {
    u(0) = r.u[t];
    if (oe_reg.Next(u, z4)) {
      w[t] = theta_oe(0) * r.u[t - 1] + theta_oe(1) * r.u[t - 2] - theta_oe(2) * w[t - 1] - theta_oe(3) * w[t - 2];
      EXPECT_NEAR(theta_oe.dot(z4), w[t], 1e-12 * (1 + std::abs(w[t])) * t) << "t = " << t;
    } else {
      w[t] = r.y[t];
    }
    // From t0 on the measured output does not enter an OE regressor (before, it seeds w).
    oe_reg.PushOutput(t < oe.first_regression_index() ? r.y[t] : r.y[t] + 100.0);
  }
}

TEST(PseudoLinearRegressor, TrackEstimateKeepsTheLastStableOne) {
  PseudoLinearRegressor reg(PolynomialStructure::OutputError(1, 1, 1));
  Eigen::VectorXd stable(2), unstable(2);
  stable << 1.0, -0.5;
  unstable << 1.0, -1.5;                     // F = 1 − 1.5 q⁻¹: root 1.5
  EXPECT_TRUE(reg.TrackEstimate(unstable));  // the first estimate is taken whatever it is
  EXPECT_TRUE(reg.TrackEstimate(stable));
  for (int k = 0; k < PseudoLinearRegressor::kWarmUp * 2; ++k) reg.TrackEstimate(stable);  // past the warm-up
  EXPECT_FALSE(reg.TrackEstimate(unstable));
  EXPECT_EQ(reg.projections(), 1);
  // The kept estimate is the stable one: w(t) = u(t−1) + 0.5 w(t−1).
  Eigen::VectorXd z(2), u(1);
  double w = 0;
  for (int t = 0; t < 20; ++t) {
    u(0) = 1.0;
    if (reg.Next(u, z)) {
      w = 1.0 + 0.5 * w;
      EXPECT_NEAR(stable.dot(z), w, 1e-12);
    } else {
      w = 0.0;
    }
    reg.PushOutput(0.0);
  }
  reg.SetEstimate(unstable);                // a fixed model is used as given
  EXPECT_FALSE(reg.TrackEstimate(stable));  // and held until ClearEstimate
  reg.ClearEstimate();
  EXPECT_TRUE(reg.TrackEstimate(stable));
}

}  // namespace
}  // namespace ident::models

namespace ident::models {
namespace {

// RPEM: while an estimate is tracked after the warm-up, z is the gradient ψ = φ/C (filtered from the φ of
// the same θ used as a fixed model) and the linearised output is y + θ'(ψ − φ); during the warm-up z = φ.
TEST(PseudoLinearRegressor, PredictionErrorGradientIsPhiFilteredByC) {
  const Record r = SimulateArmax({-1.5, 0.7}, {1.0, 0.5}, {-1.0, 0.2}, 1, 120, 6);
  const auto armax = PolynomialStructure::Armax(2, {2}, 2, {1});
  Eigen::VectorXd theta(6);
  theta << -1.4, 0.6, 0.9, 0.4, -0.8, 0.1;
  PseudoLinearRegressor fixed(armax), rpem(armax, {}, Recursion::kPredictionError);
  fixed.SetEstimate(theta);
  for (int k = 0; k < PseudoLinearRegressor::kWarmUp * 6; ++k) rpem.TrackEstimate(theta);  // past the warm-up
  Eigen::VectorXd phi(6), psi(6), u(1);
  std::vector<Eigen::VectorXd> past(2, Eigen::VectorXd::Zero(6));
  for (int t = 0; t < 120; ++t) {
    u(0) = r.u[t];
    rpem.TrackEstimate(theta);
    const bool formed = fixed.Next(u, phi);
    EXPECT_EQ(rpem.Next(u, psi), formed);
    if (formed) {
      const Eigen::VectorXd expected = phi - theta(4) * past[0] - theta(5) * past[1];
      EXPECT_LT((psi - expected).cwiseAbs().maxCoeff(), 1e-9 * (1 + expected.cwiseAbs().maxCoeff())) << "t = " << t;
      EXPECT_NEAR(rpem.LinearisedOutput(r.y[t]), r.y[t] + theta.dot(expected - phi), 1e-9) << "t = " << t;
      past[1] = past[0];
      past[0] = expected;
    }
    fixed.PushOutput(r.y[t]);
    rpem.PushOutput(r.y[t]);
  }
}

// The prediction errors ε(t; θ) of a fixed Box–Jenkins model θ over a record (SetEstimate: the regressor's
// residual, noise and noise-free output histories all come from θ).
std::vector<double> FixedModelErrors(const PolynomialStructure& s, const Eigen::VectorXd& theta, const Record& r) {
  PseudoLinearRegressor fixed(s);
  fixed.SetEstimate(theta);
  Eigen::VectorXd phi(theta.size()), u(1);
  std::vector<double> e(r.y.size(), 0.0);
  for (std::size_t t = 0; t < r.y.size(); ++t) {
    u(0) = r.u[t];
    if (fixed.Next(u, phi)) e[t] = r.y[t] - theta.dot(phi);
    fixed.PushOutput(r.y[t]);
  }
  return e;
}

// RPEM on Box–Jenkins: ψ(t) is −∂ε(t; θ)/∂θ, checked by central differences of the fixed model's errors,
// coordinate by coordinate (D(q)φ/(C(q)F(q)) in the B and F coordinates, φ/C in the C and D ones).
TEST(PseudoLinearRegressor, BoxJenkinsPredictionErrorGradientIsMinusTheErrorsDerivative) {
  const Record r = SimulateArmax({-1.5, 0.7}, {1.0, 0.5}, {-1.0, 0.2}, 1, 200, 11);
  const auto bj = PolynomialStructure::BoxJenkins(2, 2, 1, 2, 1);  // θ = [b1 b2, c1 c2, d1, f1 f2]
  Eigen::VectorXd theta(7);
  theta << 0.9, 0.4, -0.6, 0.2, -0.5, -1.2, 0.5;
  std::vector<std::vector<double>> derivative(7);
  for (int j = 0; j < 7; ++j) {
    const double h = 1e-6;
    Eigen::VectorXd up = theta, down = theta;
    up(j) += h;
    down(j) -= h;
    const std::vector<double> eu = FixedModelErrors(bj, up, r), ed = FixedModelErrors(bj, down, r);
    for (std::size_t t = 0; t < eu.size(); ++t) derivative[j].push_back(-(eu[t] - ed[t]) / (2 * h));
  }
  PseudoLinearRegressor rpem(bj, {}, Recursion::kPredictionError);
  for (int k = 0; k < PseudoLinearRegressor::kWarmUp * 7; ++k) rpem.TrackEstimate(theta);  // past the w = y warm-up
  Eigen::VectorXd psi(7), u(1);
  int formed = 0;
  for (std::size_t t = 0; t < r.y.size(); ++t) {
    u(0) = r.u[t];
    ASSERT_TRUE(rpem.TrackEstimate(theta));
    if (rpem.Next(u, psi)) {
      ++formed;
      for (int j = 0; j < 7; ++j)
        EXPECT_NEAR(psi(j), derivative[j][t], 1e-6 * (1 + std::abs(derivative[j][t]))) << "t = " << t << ", j = " << j;
    }
    rpem.PushOutput(r.y[t]);
  }
  EXPECT_GT(formed, 190);
  // During the warm-up (w = y) the regressor is φ, as in pseudo-linear regression.
  PseudoLinearRegressor warm(bj, {}, Recursion::kPredictionError), plain(bj);
  Eigen::VectorXd phi(7);
  for (std::size_t t = 0; t < 20; ++t) {
    u(0) = r.u[t];
    warm.TrackEstimate(theta);
    plain.TrackEstimate(theta);
    const bool a = warm.Next(u, psi), b = plain.Next(u, phi);
    ASSERT_EQ(a, b);
    if (a) {
      EXPECT_EQ(psi, phi) << "t = " << t;
    }
    EXPECT_EQ(warm.LinearisedOutput(r.y[t]), r.y[t]);
    warm.PushOutput(r.y[t]);
    plain.PushOutput(r.y[t]);
  }
}

}  // namespace
}  // namespace ident::models
