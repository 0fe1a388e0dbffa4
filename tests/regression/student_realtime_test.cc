// Real-time loop features of the Kárný–Hangos Cauchy/Student-t estimator (fixed-size ρ = 4 and
// dynamic), as for RLS: skip/enable leave the state bit-identical, Reset() equals a freshly built
// estimator (explicit and data-driven priors), the multivariate-t covariance at any time without
// allocation (checked against a dense recomputation of V from the reported weights), forgetting
// changed on the fly (checked against a dense recursion with the weighting cubic solved on dense ξ,
// ξ_z) and refused when inadmissible, and zero allocations over 10^4 mixed loop operations.
#include <cmath>
#include <cstring>
#include <random>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Cholesky>

#include "approx/weighting_polynomial.h"
#include "common/dense_decompositions.h"
#include "ident/regression/student_regression.h"
#include "tests/regression/arx_stream.h"
#include "tests/support/alloc_counter.h"

namespace ident {
namespace {

// ARX(2,2) data with 5 % outliers of ±5.
std::vector<testing::ArxSample> ArxDataWithOutliers(unsigned seed, int count) {
  return testing::ArxData(seed, count, 0.05);
}

// Bitwise equality of the whole estimator state (factor L, D, ν, last β, start-up window position).
template <class E>
bool SameStudentStateBits(const E& a, const E& b) {
  const auto& fa = a.statistics().factor();
  const auto& fb = b.statistics().factor();
  const double na = a.nu(), nb = b.nu(), ba = a.beta(), bb = b.beta();
  return fa.L().size() == fb.L().size() &&
         std::memcmp(fa.L().data(), fb.L().data(), sizeof(double) * fa.L().size()) == 0 &&
         std::memcmp(fa.d().data(), fb.d().data(), sizeof(double) * fa.d().size()) == 0 &&
         std::memcmp(&na, &nb, sizeof na) == 0 && std::memcmp(&ba, &bb, sizeof ba) == 0 &&
         a.in_startup() == b.in_startup() && a.prior().nu0 == b.prior().nu0 && a.prior().V0 == b.prior().V0;
}

// Cauchy (k = 1, δ = 1), ν0 = ρ+k+δ = 6, V0 = diag(1, 0.01 I).
StudentRegressionOptions Cauchy(double lambda, bool stabilised = false) {
  StudentRegressionOptions o;
  o.forgetting = {lambda, stabilised};
  o.prior = RegressionPrior::Diagonal(4, 6, 1, 0.01);
  return o;
}

template <class E>
class StudentRealtime : public ::testing::Test {};
using StudentVariants = ::testing::Types<BasicStudentRegression<4>, BasicStudentRegression<Eigen::Dynamic>>;
TYPED_TEST_SUITE(StudentRealtime, StudentVariants);

TYPED_TEST(StudentRealtime, LoopOperationsAreNoexcept) {
  TypeParam est(4, Cauchy(0.99));
  const Eigen::Vector4d z = Eigen::Vector4d::Ones();
  static_assert(noexcept(est.Update(1.0, z)));
  static_assert(noexcept(est.Skip()));
  static_assert(noexcept(est.Reset()));
  static_assert(noexcept(est.set_enabled(false)));
  EXPECT_EQ(est.Skip().status, StepStatus::kSkipped);
}

TYPED_TEST(StudentRealtime, DisabledUpdatesLeaveTheStateBitIdenticalAndResumeExactly) {
  for (const bool stabilised : {false, true}) {
    const auto data = ArxDataWithOutliers(31, 400);
    TypeParam est(4, Cauchy(0.98, stabilised));
    TypeParam twin(4, Cauchy(0.98, stabilised));  // never sees samples 100..149
    for (int t = 0; t < 400; ++t) {
      const bool gate = t >= 100 && t < 150;
      est.set_enabled(!gate);
      EXPECT_EQ(est.enabled(), !gate);
      const TypeParam before = est;
      const StepReport r = est.Update(data[t].y, data[t].z);
      if (gate) {
        ASSERT_EQ(r.status, StepStatus::kSkipped);
        ASSERT_TRUE(SameStudentStateBits(est, before)) << "t = " << t;
        ASSERT_EQ(est.Predict(data[t].z), before.Predict(data[t].z));
      } else {
        ASSERT_TRUE(r.updated()) << "t = " << t;
        twin.Update(data[t].y, data[t].z);
      }
    }
    EXPECT_TRUE(SameStudentStateBits(est, twin)) << "stabilised = " << stabilised;
    EXPECT_EQ(est.parameters(), twin.parameters());
  }
}

TYPED_TEST(StudentRealtime, SkippedMissingSamplesLeaveTheStateBitIdentical) {
  const auto data = ArxDataWithOutliers(32, 300);
  StudentRegressionOptions o;  // default: data-driven start-up — skipped samples do not enter the window
  o.forgetting.factor = 0.99;
  TypeParam est(4, o);
  TypeParam twin(4, o);
  for (int t = 0; t < 300; ++t) {
    if (t % 7 == 3) {
      const TypeParam before = est;
      ASSERT_EQ(est.Skip().status, StepStatus::kSkipped);
      ASSERT_TRUE(SameStudentStateBits(est, before));
      ASSERT_EQ(est.Update(std::nan(""), data[t].z).status, StepStatus::kRejectedInvalid);
      ASSERT_TRUE(SameStudentStateBits(est, before));
    } else {
      est.Update(data[t].y, data[t].z);
      twin.Update(data[t].y, data[t].z);
    }
  }
  EXPECT_FALSE(est.in_startup());
  EXPECT_TRUE(SameStudentStateBits(est, twin));
}

TYPED_TEST(StudentRealtime, ResetEqualsAFreshlyBuiltEstimator) {
  const auto data = ArxDataWithOutliers(33, 300);
  StudentRegressionOptions data_driven;
  data_driven.forgetting.factor = 0.99;
  for (const StudentRegressionOptions& o : {Cauchy(0.97, true), data_driven}) {
    TypeParam est(4, o);
    const TypeParam fresh(4, o);
    for (int t = 0; t < 120; ++t) est.Update(data[t].y, data[t].z);
    ASSERT_FALSE(SameStudentStateBits(est, fresh));
    est.Reset();
    EXPECT_TRUE(SameStudentStateBits(est, fresh));
    EXPECT_EQ(est.in_startup(), !o.prior.has_value());
    // The prior guess Θ̂(0) = V_z⁻¹V_zy = 0 for a diagonal V0.
    EXPECT_EQ(est.parameters(), Eigen::Vector4d::Zero());
    TypeParam again(4, o);
    for (int t = 120; t < 300; ++t) {
      ASSERT_EQ(est.Update(data[t].y, data[t].z).status, again.Update(data[t].y, data[t].z).status);
    }
    EXPECT_TRUE(SameStudentStateBits(est, again));
    EXPECT_EQ(est.parameters(), again.parameters());
  }
}

// The dense reference of one step: V ← (1−β)V + βhh', h = [y; z], with the reported β [spec §3].
template <class Z>
void DenseStep(Eigen::MatrixXd& V, const StepReport& r, double y, const Z& z) {
  Eigen::VectorXd h(z.size() + 1);
  h << y, z;
  V = (1 - r.weight) * V + r.weight * h * h.transpose();
}

// The posterior's Cov(Θ) = D_y V_z⁻¹/(ν−δ−ρ) [spec §2]. Reference: V recomputed densely from the reported
// weights, V(t) = (1−β_t)V(t−1) + β_t h h' (exponential forgetting leaves V unchanged [spec §7b]),
// ν(t) = λν + 1, D_y = V_y − V_zy'V_z⁻¹V_zy, the inverse by Cholesky.
TYPED_TEST(StudentRealtime, PosteriorCovarianceAtAnyTimeEqualsTheDenseMultivariateT) {
  const auto data = ArxDataWithOutliers(34, 400);
  const StudentRegressionOptions o = Cauchy(0.99);
  TypeParam est(4, o);
  Eigen::MatrixXd V = o.prior->V0;
  double nu = o.prior->nu0;
  Eigen::Matrix4d P;
  for (int t = 0; t < 400; ++t) {
    const StepReport r = est.Update(data[t].y, data[t].z);
    ASSERT_TRUE(r.updated());
    DenseStep(V, r, data[t].y, data[t].z);
    nu = 0.99 * nu + 1;
    if (t != 0 && t != 30 && t != 399) continue;
    const Eigen::LLT<Eigen::MatrixXd> Vz = dense::Llt(V.bottomRightCorner(4, 4));
    const Eigen::VectorXd Vzy = V.bottomLeftCorner(4, 1);
    const double Dy = V(0, 0) - Vzy.dot(Vz.solve(Vzy));
    const Eigen::MatrixXd cov = Dy / (nu - 1 - 4) * Vz.solve(Eigen::MatrixXd::Identity(4, 4));
    est.PosteriorCovarianceInto(P);
    EXPECT_NEAR(est.nu(), nu, 1e-12 * nu) << "t = " << t;
    EXPECT_LT((P - cov).norm(), 1e-9 * cov.norm()) << "t = " << t;
    EXPECT_LT((P - est.posterior_covariance()).norm(), 1e-14 * cov.norm()) << "t = " << t;
    EXPECT_EQ(P, P.transpose());
  }
}

// The sampling covariance: the larger of two variance factors times V_z⁻¹ [ident/regression/student_regression.h].
// The sandwich c/n, c = κ²·n/(n−ρ)·mean(ψ²)/mean(ψ')², κ = 1 + (ρ/n)·var(ψ')/mean(ψ')², ψ = wê,
// ψ' = (k+1)(k−u)/(k+u)², w = (k+1)/(k+u), u = ξ_z − ξ, means discounted by λ; and the propagated
// s(t) = ((1−c)² + (ρ−1)c²)s(t−1) + (q/ρ)(gê)², c = γq/ρ, q = 1 − ξ_z, g = β/(1−βξ_z), γ = g + ê·dg/dê, from
// s(0) = D_y(0)/(ν0−δ−ρ). Reference: the sums formed here from the step reports and details, dβ/dê by central
// differences of the weighting problem's solution, V_z densely from the reported weights as above.
TYPED_TEST(StudentRealtime, CovarianceIsTheLargerOfSandwichAndPropagationAtAnyTime) {
  const auto data = ArxDataWithOutliers(35, 400);
  const StudentRegressionOptions o = Cauchy(0.99);
  TypeParam est(4, o);
  Eigen::MatrixXd V = o.prior->V0;
  double psi2 = 0, dpsi = 0, dpsi2 = 0, n = 0;
  const double dy0 =
      V(0, 0) - (V.block(0, 1, 1, 4) * dense::Llt(V.bottomRightCorner(4, 4)).solve(V.block(1, 0, 4, 1)))(0, 0);
  double s = dy0 / (o.prior->nu0 - 1 - 4);
  int propagated_larger = 0;
  Eigen::Matrix4d P;
  for (int t = 0; t < 400; ++t) {
    const StepReport r = est.Update(data[t].y, data[t].z);
    ASSERT_TRUE(r.updated());
    DenseStep(V, r, data[t].y, data[t].z);
    const double xi = est.last_step().xi, xi_z = est.last_step().xi_z, u = xi_z - xi, w = 2 / (1 + u);
    psi2 = 0.99 * psi2 + w * w * r.prediction_error * r.prediction_error;
    const double d = 2 * (1 - u) / ((1 + u) * (1 + u));
    dpsi = 0.99 * dpsi + d;
    dpsi2 = 0.99 * dpsi2 + d * d;
    n = 0.99 * n + 1;
    auto beta_at = [&](double uu) { return approx::SolveWeight({r.nu, xi_z - uu, xi_z, 4, 1.0, 1}).beta; };
    ASSERT_NEAR(beta_at(u), r.weight, 1e-12 * r.weight) << t;
    const double h = 1e-5 * u, elasticity = 2 * u * (beta_at(u + h) - beta_at(u - h)) / (2 * h);
    const double q = 1 - xi_z, a = 1 - r.weight * xi_z, g = r.weight / a;
    const double c_step = (g + elasticity / (a * a)) * q / 4, ge = g * r.prediction_error;
    s = ((1 - c_step) * (1 - c_step) + 3 * c_step * c_step) * s + q / 4 * ge * ge;
    est.CovarianceInto(P);
    if (t < 5) {  // n ≤ ρ + 1
      EXPECT_TRUE((P.array() == std::numeric_limits<double>::infinity()).all()) << t;
      continue;
    }
    const double m = dpsi / n, kappa = 1 + 4 / n * (dpsi2 / n - m * m) / (m * m);
    const double sandwich = kappa * kappa * n / (n - 4) * (psi2 / n) / (m * m) / n;
    propagated_larger += s > sandwich;
    if (t != 5 && t != 30 && t != 399) continue;
    const Eigen::MatrixXd cov =
        std::max(s, sandwich) * dense::Llt(V.bottomRightCorner(4, 4)).solve(Eigen::MatrixXd::Identity(4, 4));
    EXPECT_LT((P - cov).norm(), 1e-6 * cov.norm()) << "t = " << t;
    EXPECT_LT((P - est.covariance()).norm(), 1e-14 * cov.norm()) << "t = " << t;
  }
  EXPECT_GT(propagated_larger, 0);  // both read-outs are exercised
}

TYPED_TEST(StudentRealtime, PosteriorCovarianceIsInfiniteWhileNuIsAtMostDeltaPlusRho) {
  StudentRegressionOptions o;
  o.prior = RegressionPrior::Diagonal(4, 4.5, 1, 0.01);  // ν0 − δ − ρ = −0.5; ν(1) = 5.5 > ν_hard = 4
  TypeParam est(4, o);
  Eigen::Matrix4d P;
  est.PosteriorCovarianceInto(P);
  EXPECT_TRUE((P.array() == std::numeric_limits<double>::infinity()).all());
  est.Update(1.0, Eigen::Vector4d(1, 0, 0, 0));  // ν = 5.5: finite
  est.PosteriorCovarianceInto(P);
  EXPECT_TRUE(P.allFinite());
}

TYPED_TEST(StudentRealtime, CovarianceIntoRejectsAWrongSizeNamingIt) {
  TypeParam est(4, Cauchy(1));
  Eigen::Matrix3d P;
  try {
    est.CovarianceInto(P);
    FAIL() << "expected InvalidArgument";
  } catch (const InvalidArgument& e) {
    EXPECT_STREQ(e.what(), "covariance output is 3x3; need 4x4");
  }
}

// Forgetting changed on the fly: λ_t for step t. Reference: the dense recursion ν(t) = λ_t ν + 1,
// V(t) = (1−β)V + βhh' with β the maximin root of the weighting cubic (approx::SolveWeight, verified
// against brute force in tests/approx) for ξ = 1 − h'V⁻¹h, ξ_z = 1 − z'V_z⁻¹z computed densely.
TYPED_TEST(StudentRealtime, ForgettingChangedOnTheFlyEqualsTheDenseRecursion) {
  const auto data = ArxDataWithOutliers(35, 600);
  const StudentRegressionOptions o = Cauchy(1.0);
  TypeParam est(4, o);
  Eigen::MatrixXd V = o.prior->V0;
  double nu = o.prior->nu0, max_beta_diff = 0;
  for (int t = 0; t < 600; ++t) {
    const double lambda = t < 200 ? 1.0 : t < 400 ? 0.95 : 0.99;
    est.set_forgetting(lambda);
    EXPECT_EQ(est.options().forgetting.factor, lambda);
    const StepReport r = est.Update(data[t].y, data[t].z);
    ASSERT_TRUE(r.updated());
    Eigen::VectorXd h(5);
    h << data[t].y, data[t].z;
    const Eigen::VectorXd z = h.tail(4);
    nu = lambda * nu + 1;
    const double xi = 1 - h.dot(dense::Ldlt(V).solve(h));
    const double xi_z = 1 - z.dot(dense::Ldlt(V.bottomRightCorner(4, 4)).solve(z));
    const approx::WeightSolution w = approx::SolveWeight({nu, xi, xi_z, 4, 1.0, 1});
    ASSERT_TRUE(w.ok);
    max_beta_diff = std::max(max_beta_diff, std::abs(w.beta - r.weight) / w.beta);
    V = (1 - w.beta) * V + w.beta * h * h.transpose();
  }
  EXPECT_NEAR(est.nu(), nu, 1e-12 * nu);
  EXPECT_LT(max_beta_diff, 1e-8);
  const Eigen::VectorXd theta = dense::Ldlt(V.bottomRightCorner(4, 4)).solve(V.bottomLeftCorner(4, 1));
  EXPECT_LT((est.parameters() - theta).norm(), 1e-8 * theta.norm());
}

TYPED_TEST(StudentRealtime, InadmissibleForgettingIsRefusedAndLeavesTheOldOne) {
  TypeParam est(4, Cauchy(0.99));  // ν_hard = max(ρ+δ−1, (k+3−δ)/k, ρ/(k+1)) = 4
  EXPECT_THROW(est.set_forgetting(1.5), InvalidArgument);
  try {
    est.set_forgetting(0.7);  // ν(t) → 1/(1−λ) = 3.33 ≤ 4
    FAIL() << "expected InvalidArgument";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("forgetting = 0.7 is inadmissible"), std::string::npos) << e.what();
  }
  EXPECT_EQ(est.options().forgetting.factor, 0.99);
  est.set_forgetting(0.8);  // 1/(1−λ) = 5 > 4
  EXPECT_EQ(est.options().forgetting.factor, 0.8);
}

TYPED_TEST(StudentRealtime, TenThousandLoopIterationsAllocateNothing) {
  const auto data = ArxDataWithOutliers(37, 10000);
  StudentRegressionOptions data_driven;  // the start-up restart runs inside the counted loop
  data_driven.forgetting.factor = 0.99;
  for (const StudentRegressionOptions& o : {Cauchy(0.99, true), data_driven}) {
    TypeParam est(4, o);
    Eigen::Matrix4d P;
    int updated = 0, skipped = 0;
    double sink = 0;
    testing::AllocationCounter counter;
    for (int t = 0; t < 10000; ++t) {
      est.set_enabled(t % 500 < 480);
      if (t % 1000 == 10) est.set_forgetting(t % 2000 == 10 ? 0.98 : 0.995);
      const StepReport r = t % 11 == 5 ? est.Skip() : est.Update(data[t].y, data[t].z);
      updated += r.updated();
      skipped += r.status == StepStatus::kSkipped;
      est.CovarianceInto(P);  // +inf until ρ+2 updates after a Reset()
      sink += std::isfinite(P(0, 0)) ? P(0, 0) : 0;
      est.PosteriorCovarianceInto(P);
      sink += est.parameters()(0) + est.Predict(data[t].z) + P(0, 0);
      if (t == 5000) est.Reset();
    }
    EXPECT_EQ(counter.allocations(), 0);
    EXPECT_EQ(updated + skipped, 10000);
    EXPECT_GT(skipped, 800);
    EXPECT_TRUE(std::isfinite(sink));
    EXPECT_LT((est.parameters() - Eigen::Vector4d(-1.5, 0.7, 1.0, 0.5)).norm(), 0.05);
  }
}

}  // namespace
}  // namespace ident
