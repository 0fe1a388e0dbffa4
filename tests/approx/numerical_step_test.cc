// The generic numerical maximin step (essinf by minimisation, integral by quadrature, Brent over β)
// against the closed forms: the Student/Cauchy cubic root and the Gaussian β = 1/ν (ρ = 1 and 2) [issue item 1].
// At ρ = 2 one evaluation (a 3-D quadrature and a 3-D minimisation) takes about a second, so the maximin β there
// is checked as the vertex of the numerical objective around the closed-form root instead of by the full search.
// The ρ = 2 tests are skipped under the sanitizer: there an evaluation (1.4e7 instrumented integrand calls) takes
// about a minute (the three tests 211 CPU-s, a sixth of the CI budget); the sanitizer suite runs the same
// functions at ρ = 1 above.
#include "approx/numerical_step.h"

#include <cmath>
#include <cstdio>

#include <gtest/gtest.h>

#include "approx/weighting_polynomial.h"
#include "tests/support/sanitizer.h"

namespace ident::approx {
namespace {

double Residual(const Eigen::VectorXd& h, const Eigen::VectorXd& theta) {
  return h(0) - theta.dot(h.tail(h.size() - 1));
}

// log m(h|Θ, ω) of Student-t noise with k degrees of freedom (k = 1: Cauchy) [spec §1].
LogModelFn StudentModel(double k) {
  return [kappa = (k + 1) / 2](const Eigen::VectorXd& h, const Eigen::VectorXd& th, double w) {
    const double e = Residual(h, th);
    return 0.5 * std::log(w) - kappa * std::log1p(w * e * e);
  };
}

TEST(NumericalStep, AgreesWithTheCubicRootForCauchyAndStudent) {
  struct Case {
    double k, nu, outlier;
  };
  for (const Case c : {Case{1, 4, 0.3}, Case{1, 6, 8.0}, Case{3, 5, 2.0}}) {
    Eigen::MatrixXd V(2, 2);
    V << 1.0, 0.3, 0.3, 0.5;
    const NormalisedStatistics s{c.nu, V};
    Eigen::VectorXd h(2);
    h << 0.6 * 0.8 + c.outlier, 0.8;
    const LogModelFn log_m = StudentModel(c.k);
    const OneSidedStepResult num = NumericalStep(s, h, log_m, StudentShape{c.k}, 1);
    const OneSidedStepResult closed = StudentClass{c.k, 1}.Step(s, h);
    EXPECT_NEAR(num.beta / closed.beta, 1, 2e-7)
        /* seen: up to 9.2e-8 */ << "k=" << c.k << " nu=" << c.nu << " outlier=" << c.outlier;
    // The numerical log γ and log ∫ at the closed-form β match the closed forms of spec §2–§3.
    const OneSidedStepResult at = NumericalEvaluate(s, h, closed.beta, log_m, StudentShape{c.k}, 1);
    EXPECT_NEAR(at.log_integral, closed.log_integral, 1e-7);
    EXPECT_NEAR(at.log_gamma, closed.log_gamma, 1e-6);
  }
}

TEST(NumericalStep, GaussianModelGivesOneOverNu) {
  Eigen::MatrixXd V(2, 2);
  V << 1.0, -0.2, -0.2, 0.7;
  const NormalisedStatistics s{5, V};
  Eigen::VectorXd h(2);
  h << 0.4, 1.1;
  auto log_m = [](const Eigen::VectorXd& hh, const Eigen::VectorXd& th, double w) {
    const double e = Residual(hh, th);
    return 0.5 * std::log(w) - w * e * e / 2;
  };
  const OneSidedStepResult num = NumericalStep(s, h, log_m, GaussianShape{}, 1);
  EXPECT_NEAR(num.beta * 6, 1, 2e-7);  // seen: 6.6e-8
  EXPECT_NEAR(NumericalEvaluate(s, h, 1.0 / 6, log_m, GaussianShape{}, 1).log_integral,
              GaussianClass{}.Evaluate(s, h, 1.0 / 6).log_integral, 1e-7);
}

// ρ = 2: V 3x3, h = (y, z1, z2).
NormalisedStatistics RhoTwoStatistics(double nu) {
  Eigen::MatrixXd V(3, 3);
  V << 1.0, 0.3, -0.2, 0.3, 0.5, 0.1, -0.2, 0.1, 0.8;
  return {nu, V};
}

TEST(NumericalStep, RhoTwoLogGammaAndLogIntegralMatchTheClosedForms) {
  if (testing::kUnderSanitizer) GTEST_SKIP() << "rho = 2 quadrature: Release suite only (see the header)";
  struct Case {
    double k, nu, outlier;
  };
  const Case cases[] = {{1, 6, 0.2}, {1, 7, 6.0}, {3, 6, 1.5}};
  for (const Case& c : cases) {
    const NormalisedStatistics s = RhoTwoStatistics(c.nu);
    Eigen::VectorXd h(3);
    h << 0.5 * 0.8 - 0.3 * 0.4 + c.outlier, 0.8, -0.4;
    const OneSidedStepResult closed = StudentClass{c.k, 1}.Step(s, h);
    const OneSidedStepResult at = NumericalEvaluate(s, h, closed.beta, StudentModel(c.k), StudentShape{c.k}, 1);
    std::printf("[ measured ] rho = 2, k = %g, nu = %g: log integral %+.3g, log gamma %+.3g off the closed forms\n",
                c.k, c.nu, at.log_integral - closed.log_integral, at.log_gamma - closed.log_gamma);
    EXPECT_NEAR(at.log_integral, closed.log_integral, 1e-7) << "k=" << c.k << " outlier=" << c.outlier;
    EXPECT_NEAR(at.log_gamma, closed.log_gamma, 1e-6) << "k=" << c.k << " outlier=" << c.outlier;
  }
}

// The numerical objective log γ + log ∫ at β·e^{−d}, β, β·e^{d}: the closed-form β is its maximum, and the
// vertex of the parabola through the three values (in log β) lies on it to O(d²).
TEST(NumericalStep, RhoTwoClosedFormRootIsTheMaximumOfTheNumericalObjective) {
  if (testing::kUnderSanitizer) GTEST_SKIP() << "rho = 2 quadrature: Release suite only (see the header)";
  const NormalisedStatistics s = RhoTwoStatistics(7);
  Eigen::VectorXd h(3);
  h << 2.5, 0.8, -0.4;  // ê ≈ 2.2: a moderate outlier, β well inside (β0, β_hi)
  const OneSidedStepResult closed = StudentClass{1, 1}.Step(s, h);
  const double d = 1e-3;
  double J[3];
  for (int i = 0; i < 3; ++i)
    J[i] =
        NumericalEvaluate(s, h, closed.beta * std::exp((i - 1) * d), StudentModel(1), StudentShape{1}, 1).objective();
  EXPECT_GT(J[1], J[0]);
  EXPECT_GT(J[1], J[2]);
  const double vertex = d * (J[0] - J[2]) / (2 * (J[0] - 2 * J[1] + J[2]));  // in log β, relative to the root
  std::printf("[ measured ] rho = 2: numerical maximum at beta*(1 %+.3g), closed-form beta = %.10g\n", vertex,
              closed.beta);
  EXPECT_LT(std::abs(vertex), 1e-5) << "numerical maximum at beta*(1 + " << vertex << ")";
}

TEST(NumericalStep, RhoTwoGaussianLogIntegralMatchesTheNormalGammaClass) {
  if (testing::kUnderSanitizer) GTEST_SKIP() << "rho = 2 quadrature: Release suite only (see the header)";
  const NormalisedStatistics s = RhoTwoStatistics(5);
  Eigen::VectorXd h(3);
  h << 0.4, 1.1, 0.3;
  auto log_m = [](const Eigen::VectorXd& hh, const Eigen::VectorXd& th, double w) {
    const double e = Residual(hh, th);
    return 0.5 * std::log(w) - w * e * e / 2;
  };
  const OneSidedStepResult num = NumericalEvaluate(s, h, 1.0 / 6, log_m, GaussianShape{}, 1);
  const OneSidedStepResult closed = GaussianClass{}.Evaluate(s, h, 1.0 / 6);
  EXPECT_NEAR(num.log_integral, closed.log_integral, 1e-7);
  // (log γ is 0 here by exact cancellation, −ω(νβ−1)(…) with νβ = 1; the numerical minimisation over
  // ω ≤ e^40 sees the rounding of two terms of size ~1e20 instead, as at ρ = 1 — not a check of anything.)
}

}  // namespace
}  // namespace ident::approx
