// The generic numerical maximin step (essinf by minimisation, integral by quadrature, Brent over β)
// against the closed forms: the Student/Cauchy cubic root and the Gaussian β = 1/ν (ρ = 1) [issue item 1].
#include "approx/numerical_step.h"

#include <cmath>

#include <gtest/gtest.h>

#include "approx/weighting_polynomial.h"

namespace ident::approx {
namespace {

double Residual(const Eigen::VectorXd& h, const Eigen::VectorXd& theta) {
  return h(0) - theta.dot(h.tail(h.size() - 1));
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
    const double kappa = (c.k + 1) / 2;
    auto log_m = [&](const Eigen::VectorXd& hh, const Eigen::VectorXd& th, double w) {
      const double e = Residual(hh, th);
      return 0.5 * std::log(w) - kappa * std::log1p(w * e * e);
    };
    const OneSidedStepResult num = NumericalStep(s, h, log_m, StudentShape{c.k}, 1);
    const OneSidedStepResult closed = StudentClass{c.k, 1}.Step(s, h);
    EXPECT_NEAR(num.beta / closed.beta, 1, 2e-7)  /* seen: up to 9.2e-8 */ << "k=" << c.k << " nu=" << c.nu << " outlier=" << c.outlier;
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

}  // namespace
}  // namespace ident::approx
