// Pole placement (Diophantine equation) and the RST law: hand-solved cases, the identity
// A'R̄ + BS = Ac on random models, closed-loop simulation against the designed transfer function
// t0·B/Am, loss of controllability reported, zero allocations per design + control step.
#include "ident/control/pole_placement.h"

#include <random>

#include <gtest/gtest.h>

#include "common/error.h"
#include "ident/control/rst_controller.h"
#include "tests/support/alloc_counter.h"

namespace ident::control {
namespace {

PolePlacementOptions Options(Eigen::VectorXd am, Eigen::VectorXd ao, bool integral) {
  PolePlacementOptions o;
  o.am = std::move(am);
  o.ao = std::move(ao);
  o.integral_action = integral;
  return o;
}

void ExpectCoefficients(const Eigen::VectorXd& got, const Eigen::VectorXd& want) {
  ASSERT_EQ(got.size(), want.size());
  for (Eigen::Index i = 0; i < want.size(); ++i) EXPECT_NEAR(got(i), want(i), 1e-12) << "coefficient " << i;
}

// A = 1 − 1.5q⁻¹ + 0.7q⁻², B = q⁻¹(1 + 0.5q⁻¹), Am = (1 − 0.5q⁻¹)², Ao = 1, no integrator.
// Coefficients of AR + BS = Am with R = 1 + r1 q⁻¹, S = s0 + s1 q⁻¹:
//   q⁻¹: −1.5 + r1 + s0 = −1;  q⁻²: 0.7 − 1.5r1 + 0.5s0 + s1 = 0.25;  q⁻³: 0.7r1 + 0.5s1 = 0
//   ⇒ r1 = 7/34, s0 = 5/17, s1 = −49/170;  t0 = Am(1)/B(1) = 0.25/1.5 = 1/6.
TEST(PolePlacement, MatchesHandSolvedCaseWithoutIntegrator) {
  PolePlacement design(2, 2, 1, Options(Eigen::Vector3d(1, -1, 0.25), Eigen::VectorXd::Ones(1), false));
  ASSERT_EQ(design.Design(Eigen::Vector2d(-1.5, 0.7), Eigen::Vector2d(1, 0.5)), DesignStatus::kOk);
  ExpectCoefficients(design.R(), Eigen::Vector2d(1, 7.0 / 34));
  ExpectCoefficients(design.S(), Eigen::Vector2d(5.0 / 17, -49.0 / 170));
  ExpectCoefficients(design.T(), Eigen::VectorXd::Constant(1, 1.0 / 6));
}

// Same plant, integrator, Ao = 1 − 0.2q⁻¹: A' = A(1 − q⁻¹) = 1 − 2.5q⁻¹ + 2.2q⁻² − 0.7q⁻³,
// Ac = Am Ao = 1 − 1.2q⁻¹ + 0.45q⁻² − 0.05q⁻³; R̄ = 1 + r1 q⁻¹, S = s0 + s1 q⁻¹ + s2 q⁻²:
//   q⁻¹: −2.5 + r1 + s0 = −1.2;  q⁻²: 2.2 − 2.5r1 + 0.5s0 + s1 = 0.45;
//   q⁻³: −0.7 + 2.2r1 + 0.5s1 + s2 = −0.05;  q⁻⁴: −0.7r1 + 0.5s2 = 0
//   ⇒ r1 = 37/102, s0 = 239/255, s1 = −223/170, s2 = 259/510;
//   R = (1 − q⁻¹)R̄ = 1 − (65/102)q⁻¹ − (37/102)q⁻²;  T = (1/6)(1 − 0.2q⁻¹).
TEST(PolePlacement, MatchesHandSolvedCaseWithIntegrator) {
  PolePlacement design(2, 2, 1, Options(Eigen::Vector3d(1, -1, 0.25), Eigen::Vector2d(1, -0.2), true));
  ASSERT_EQ(design.Design(Eigen::Vector2d(-1.5, 0.7), Eigen::Vector2d(1, 0.5)), DesignStatus::kOk);
  ExpectCoefficients(design.R(), Eigen::Vector3d(1, -65.0 / 102, -37.0 / 102));
  ExpectCoefficients(design.S(), Eigen::Vector3d(239.0 / 255, -223.0 / 170, 259.0 / 510));
  ExpectCoefficients(design.T(), Eigen::Vector2d(1.0 / 6, -0.2 / 6));
}

Eigen::VectorXd DelayedB(const Eigen::VectorXd& b, int nk) {
  Eigen::VectorXd B = Eigen::VectorXd::Zero(nk + b.size());
  B.tail(b.size()) = b;
  return B;
}

Eigen::VectorXd Padded(const Eigen::VectorXd& p, Eigen::Index n) {
  Eigen::VectorXd q = Eigen::VectorXd::Zero(n);
  q.head(p.size()) = p;
  return q;
}

TEST(PolePlacement, SolvesTheDiophantineEquationOnRandomModels) {
  std::mt19937 rng(31);
  std::uniform_real_distribution<double> coef(-1, 1);
  int checked = 0;
  for (int trial = 0; trial < 200; ++trial) {
    const int na = 1 + trial % 3, nb = 1 + (trial / 3) % 3, nk = 1 + (trial / 9) % 2;
    const bool integral = trial % 2 == 0;
    Eigen::VectorXd a(na), b(nb);
    for (auto& v : a) v = coef(rng);
    for (auto& v : b) v = coef(rng);
    b(0) += b(0) > 0 ? 0.5 : -0.5;  // keep B(1) away from 0
    const Eigen::Vector3d am(1, -1.1, 0.3);
    PolePlacementOptions o = Options(am, Eigen::Vector2d(1, -0.1), integral);
    if (!o.Validate(na, nb, nk).empty()) continue;  // Ac of too high a degree for this structure
    PolePlacement design(na, nb, nk, o);
    if (design.Design(a, b) != DesignStatus::kOk) continue;
    Eigen::VectorXd A(na + 1);
    A << 1, a;
    const Eigen::VectorXd lhs_a = Multiply(A, design.R());
    const Eigen::VectorXd lhs_b = Multiply(DelayedB(b, nk), design.S());
    const Eigen::Index n = std::max(lhs_a.size(), lhs_b.size());
    const Eigen::VectorXd lhs = Padded(lhs_a, n) + Padded(lhs_b, n);
    const Eigen::VectorXd ac = Padded(Multiply(am, o.ao), n);
    EXPECT_LT((lhs - ac).cwiseAbs().maxCoeff(), 1e-9) << "trial " << trial;
    if (integral) {
      EXPECT_NEAR(design.R().sum(), 0, 1e-12);  // R(1) = 0
    }
    EXPECT_EQ(design.R()(0), 1.0);
    ++checked;
  }
  EXPECT_GE(checked, 100);
}

// Plant A y = B u (no noise) under the RST law: y follows the designed response A_m y_m = t0 B r
// (the observer polynomial cancels), and with an integrator y(∞) = r.
TEST(PolePlacement, ClosedLoopFollowsTheDesignedTransferFunction) {
  const Eigen::Vector2d a(-1.5, 0.7), b(1, 0.5);
  const Eigen::Vector3d am(1, -1.2, 0.36);
  PolePlacement design(2, 2, 1, Options(am, Eigen::Vector2d(1, -0.3), true));
  ASSERT_EQ(design.Design(a, b), DesignStatus::kOk);
  RstController law(static_cast<int>(design.R().size()) - 1, static_cast<int>(design.S().size()) - 1,
                    static_cast<int>(design.T().size()) - 1);
  law.set_polynomials(design.R(), design.S(), design.T());
  const double t0 = am.sum() / b.sum();
  double y1 = 0, y2 = 0, u1 = 0, u2 = 0, ym1 = 0, ym2 = 0, r1 = 0, r2 = 0;
  double worst = 0, y = 0;
  for (int t = 0; t < 80; ++t) {
    const double r = t < 40 ? 1.0 : -0.5;
    y = -a(0) * y1 - a(1) * y2 + b(0) * u1 + b(1) * u2;
    const double ym = -am(1) * ym1 - am(2) * ym2 + t0 * (b(0) * r1 + b(1) * r2);
    worst = std::max(worst, std::abs(y - ym));
    const double u = law.Control(r, y);
    y2 = y1, y1 = y, u2 = u1, u1 = u, ym2 = ym1, ym1 = ym, r2 = r1, r1 = r;
  }
  EXPECT_LT(worst, 1e-9);
  EXPECT_NEAR(y, -0.5, 1e-4);  // poles at 0.6: settled 40 samples after the step
}

TEST(PolePlacement, ReportsACommonFactorAsNotControllable) {
  // A = (1 − 0.5q⁻¹)(1 + 0.3q⁻¹) = 1 − 0.2q⁻¹ − 0.15q⁻², B = q⁻¹(1 − 0.5q⁻¹).
  PolePlacement design(2, 2, 1, Options(Eigen::Vector3d(1, -1, 0.25), Eigen::VectorXd::Ones(1), false));
  ASSERT_EQ(design.Design(Eigen::Vector2d(-1.5, 0.7), Eigen::Vector2d(1, 0.5)), DesignStatus::kOk);
  const Eigen::VectorXd R = design.R(), S = design.S();
  EXPECT_EQ(design.Design(Eigen::Vector2d(-0.2, -0.15), Eigen::Vector2d(1, -0.5)), DesignStatus::kNotControllable);
  EXPECT_EQ(design.Design(Eigen::Vector2d(-0.2, 0.1), Eigen::Vector2d(1, -1)), DesignStatus::kNotControllable);
  EXPECT_EQ(design.Design(Eigen::Vector2d(NAN, 0.1), Eigen::Vector2d(1, 0.5)), DesignStatus::kInvalidModel);
  EXPECT_EQ(design.Design(Eigen::Vector3d(0, 0.1, 0), Eigen::Vector2d(1, 0.5)), DesignStatus::kInvalidModel);
  EXPECT_EQ(design.R(), R);  // the last good design is kept
  EXPECT_EQ(design.S(), S);
}

TEST(PolePlacement, RejectsInvalidOptionsNamingThem) {
  try {
    PolePlacement design(1, 1, 1, Options(Eigen::Vector3d(1, -1, 0.25), Eigen::Vector2d(1, -0.2), false));
    FAIL() << "expected InvalidArgument";
  } catch (const InvalidArgument& e) {
    EXPECT_STREQ(e.what(), "deg(am*ao) = 3; the minimum-degree design allows at most deg A' + deg B - 1 = 1");
  }
  EXPECT_THROW(PolePlacement(2, 2, 0, {}), InvalidArgument);
  EXPECT_THROW(PolePlacement(2, 0, 1, {}), InvalidArgument);
  EXPECT_THROW(PolePlacement(2, 2, 1, Options(Eigen::Vector3d(2, -1, 0.25), Eigen::VectorXd::Ones(1), true)),
               InvalidArgument);
  RstController law(2, 2, 1);
  EXPECT_THROW(law.set_polynomials(Eigen::Vector2d(1, 0), Eigen::Vector3d::Zero(), Eigen::Vector2d::Zero()),
               InvalidArgument);
  EXPECT_THROW(law.set_polynomials(Eigen::Vector3d(2, 0, 0), Eigen::Vector3d::Zero(), Eigen::Vector2d::Zero()),
               InvalidArgument);
  EXPECT_THROW(RstController(2, 2, 1, 0.0), InvalidArgument);
}

TEST(PolePlacement, DesignAndControlAllocateNothingPerSample) {
  PolePlacement design(2, 2, 1, Options(Eigen::Vector3d(1, -1.2, 0.36), Eigen::Vector2d(1, -0.3), true));
  RstController law(2, 2, 1, 5.0);
  Eigen::Vector2d a(-1.5, 0.7), b(1, 0.5);
  double sink = 0;
  int ok = 0;
  testing::AllocationCounter counter;
  for (int t = 0; t < 10000; ++t) {
    a(0) = -1.5 + 0.1 * std::sin(0.001 * t);
    if (design.Design(a, b) == DesignStatus::kOk) {
      ++ok;
      law.set_polynomials(design.R(), design.S(), design.T());
    }
    sink += law.Control(t % 200 < 100 ? 1 : -1, 0.01 * (t % 7));
  }
  EXPECT_EQ(counter.allocations(), 0);
  EXPECT_EQ(ok, 10000);
  EXPECT_TRUE(std::isfinite(sink));
}

}  // namespace
}  // namespace ident::control

namespace ident::control {
namespace {

// R = 1 − q⁻¹ (pure integrator), S = 0, T = 1: u(t) = r(t) + u(t−1), clamped to ±2. The clamped value
// enters the history, so after the reference flips the input leaves the limit at once (no wind-up):
// r = 1, 1, 1, 1, −1, −1  ⇒  u = 1, 2, 2, 2, 1, 0   (unclamped history would give 1, 2, 3, 4, 3, 2 → 2, 2).
TEST(RstController, ClampsTheInputAndFeedsBackTheAppliedValue) {
  RstController law(1, 0, 0, /*u_max=*/2);
  law.set_polynomials(Eigen::Vector2d(1, -1), Eigen::VectorXd::Zero(1), Eigen::VectorXd::Ones(1));
  const double r[] = {1, 1, 1, 1, -1, -1};
  const double want[] = {1, 2, 2, 2, 1, 0};
  for (int t = 0; t < 6; ++t) EXPECT_EQ(law.Control(r[t], 0.0), want[t]) << "t = " << t;
  law.Reset();
  EXPECT_EQ(law.Control(0.5, 0.0), 0.5);
}

// u(t) = Σ T_i r(t−i) − Σ S_i y(t−i) − Σ_{i≥1} R_i u(t−i), written out by hand for two steps.
TEST(RstController, ImplementsTheRstDifferenceEquation) {
  RstController law(2, 1, 1);
  law.set_polynomials(Eigen::Vector3d(1, 0.5, -0.25), Eigen::Vector2d(2, -1), Eigen::Vector2d(3, 0.5));
  // t = 0: u0 = 3·1 − 2·0.2 = 2.6
  EXPECT_NEAR(law.Control(1.0, 0.2), 2.6, 1e-12);
  // t = 1: u1 = 3·2 + 0.5·1 − (2·0.4 − 1·0.2) − 0.5·2.6 = 6.5 − 0.6 − 1.3 = 4.6
  EXPECT_NEAR(law.Control(2.0, 0.4), 4.6, 1e-12);
  // t = 2: u2 = 3·0 + 0.5·2 − (2·0 − 0.4) − 0.5·4.6 + 0.25·2.6 = 1 + 0.4 − 2.3 + 0.65 = −0.25
  EXPECT_NEAR(law.Control(0.0, 0.0), -0.25, 1e-12);
}

}  // namespace
}  // namespace ident::control
