// Real-time loop features of the Cauchy (Kárný–Hangos, k = 1) estimator, fixed-size ρ = 4 and dynamic:
// skip/enable leave the state bit-identical, Reset() returns exactly to the prior, CovarianceInto()
// equals covariance(), forgetting changed on the fly follows ν(t) = λ_t ν(t−1) + 1 and is refused
// when inadmissible, and 10^4 loop steps on outlier-contaminated data allocate nothing.
#include <cstring>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "ident/student_regression.h"
#include "tests/support/alloc_counter.h"

namespace ident {
namespace {

struct Sample {
  double y;
  Eigen::Vector4d z;
};

// ARX(2,2) data, θ = (−1.5, 0.7, 1.0, 0.5), Gaussian noise σ = 0.1, 2 % gross outliers (±5..10).
std::vector<Sample> ArxDataWithOutliers(unsigned seed, int count) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0, 0.1);
  std::uniform_real_distribution<double> unit(0, 1);
  const Eigen::Vector4d theta(-1.5, 0.7, 1.0, 0.5);
  std::vector<Sample> data;
  double y1 = 0, y2 = 0, u1 = 1, u2 = -1;
  for (int t = 0; t < count; ++t) {
    const Eigen::Vector4d z(-y1, -y2, u1, u2);
    const double y = theta.dot(z) + noise(rng);
    const double outlier = unit(rng) < 0.02 ? (unit(rng) < 0.5 ? -1 : 1) * (5 + 5 * unit(rng)) : 0.0;
    data.push_back({y + outlier, z});
    y2 = y1, y1 = y, u2 = u1, u1 = unit(rng) < 0.5 ? 1.0 : -1.0;
  }
  return data;
}

template <class E>
bool SameStateBits(const E& a, const E& b) {
  const auto& fa = a.statistics().factor();
  const auto& fb = b.statistics().factor();
  const double na = a.nu(), nb = b.nu();
  return fa.L().size() == fb.L().size() &&
         std::memcmp(fa.L().data(), fb.L().data(), sizeof(double) * fa.L().size()) == 0 &&
         std::memcmp(fa.d().data(), fb.d().data(), sizeof(double) * fa.d().size()) == 0 &&
         std::memcmp(&na, &nb, sizeof na) == 0;
}

StudentRegressionOptions Cauchy(double lambda, bool stabilised = false) {
  StudentRegressionOptions o;  // k = 1, δ = 1, default prior of spec §8
  o.forgetting = {lambda, stabilised};
  return o;
}

template <class E>
class CauchyRealtime : public ::testing::Test {};
using CauchyVariants = ::testing::Types<BasicStudentRegression<4>, BasicStudentRegression<Eigen::Dynamic>>;
TYPED_TEST_SUITE(CauchyRealtime, CauchyVariants);

TYPED_TEST(CauchyRealtime, LoopOperationsAreNoexcept) {
  TypeParam est(4);
  const Eigen::Vector4d z = Eigen::Vector4d::Ones();
  static_assert(noexcept(est.Update(1.0, z)));
  static_assert(noexcept(est.Skip()));
  static_assert(noexcept(est.Reset()));
  static_assert(noexcept(est.set_enabled(false)));
  EXPECT_EQ(est.Skip().status, StepStatus::kSkipped);
}

TYPED_TEST(CauchyRealtime, DisabledAndSkippedStepsLeaveTheStateBitIdentical) {
  for (const bool stabilised : {false, true}) {
    const auto data = ArxDataWithOutliers(41, 400);
    TypeParam est(4, Cauchy(0.98, stabilised));
    TypeParam twin(4, Cauchy(0.98, stabilised));  // never sees the gated samples
    for (int t = 0; t < 400; ++t) {
      const bool disabled = t >= 100 && t < 150, missing = t % 9 == 4;
      est.set_enabled(!disabled);
      const TypeParam before = est;
      const StepReport r = missing ? est.Skip() : est.Update(data[t].y, data[t].z);
      if (disabled || missing) {
        ASSERT_EQ(r.status, StepStatus::kSkipped);
        ASSERT_TRUE(SameStateBits(est, before)) << "t = " << t;
      } else {
        ASSERT_TRUE(r.updated()) << "t = " << t;
        twin.Update(data[t].y, data[t].z);
      }
    }
    EXPECT_TRUE(SameStateBits(est, twin)) << "stabilised = " << stabilised;
    EXPECT_EQ(est.parameters(), twin.parameters());
  }
}

TYPED_TEST(CauchyRealtime, ResetReturnsExactlyToThePrior) {
  const auto data = ArxDataWithOutliers(42, 200);
  TypeParam est(4, Cauchy(0.97, true));
  const TypeParam fresh(4, Cauchy(0.97, true));
  for (int t = 0; t < 120; ++t) est.Update(data[t].y, data[t].z);
  ASSERT_FALSE(SameStateBits(est, fresh));
  est.Reset();
  EXPECT_TRUE(SameStateBits(est, fresh));
  EXPECT_TRUE(std::isnan(est.beta()));
  TypeParam again(4, Cauchy(0.97, true));
  for (int t = 120; t < 200; ++t) {
    est.Update(data[t].y, data[t].z);
    again.Update(data[t].y, data[t].z);
  }
  EXPECT_TRUE(SameStateBits(est, again));
}

TYPED_TEST(CauchyRealtime, CovarianceIntoEqualsCovariance) {
  const auto data = ArxDataWithOutliers(43, 300);
  TypeParam est(4, Cauchy(0.99));
  Eigen::Matrix4d P;
  est.CovarianceInto(P);  // ν(0) = ρ + k + δ = 6 > δ + ρ = 5: finite already
  EXPECT_LT((P - est.covariance()).norm(), 1e-12 * est.covariance().norm());
  for (int t = 0; t < 300; ++t) {
    est.Update(data[t].y, data[t].z);
    if (t % 50 != 49) continue;
    est.CovarianceInto(P);
    const Eigen::MatrixXd cov = est.covariance();
    EXPECT_LT((P - cov).norm(), 1e-12 * cov.norm()) << "t = " << t;
    EXPECT_EQ(P, P.transpose());
  }
  Eigen::Matrix3d wrong;
  EXPECT_THROW(est.CovarianceInto(wrong), InvalidArgument);
}

TYPED_TEST(CauchyRealtime, ForgettingChangedOnTheFlyFollowsTheNuRecursionAndStaysAdmissible) {
  const auto data = ArxDataWithOutliers(44, 600);
  TypeParam est(4, Cauchy(1.0));
  double nu = est.nu();
  for (int t = 0; t < 600; ++t) {
    const double lambda = t < 200 ? 1.0 : t < 400 ? 0.95 : 0.99;
    est.set_forgetting(lambda);
    ASSERT_TRUE(est.Update(data[t].y, data[t].z).updated());
    nu = lambda * nu + 1;  // [spec §7b], exponential forgetting
    ASSERT_NEAR(est.nu(), nu, 1e-12 * nu) << "t = " << t;
  }
  // ν_hard = max(ρ+δ−1, (k+3−δ)/k, ρ/(k+1)) = 4 for ρ = 4, k = 1, δ = 1: λ = 0.7 drives ν towards
  // 1/(1−λ) ≈ 3.33 < 4 — refused, λ unchanged.
  EXPECT_THROW(est.set_forgetting(0.7), InvalidArgument);
  EXPECT_THROW(est.set_forgetting(0.0), InvalidArgument);
  EXPECT_EQ(est.options().forgetting.factor, 0.99);
  est.set_forgetting(0.8);  // 1/(1−0.8) = 5 > 4: admissible
  for (int t = 0; t < 100; ++t) ASSERT_TRUE(est.Update(data[t].y, data[t].z).updated());
}

TYPED_TEST(CauchyRealtime, TenThousandLoopIterationsAllocateNothing) {
  const auto data = ArxDataWithOutliers(45, 10000);
  TypeParam est(4, Cauchy(0.99, true));
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
    est.CovarianceInto(P);
    sink += est.parameters()(0) + est.Predict(data[t].z) + P(0, 0);
    if (t == 5000) est.Reset();
  }
  EXPECT_EQ(counter.allocations(), 0);
  const Eigen::MatrixXd allocating = est.covariance();  // the counter is live: this one allocates
  EXPECT_GT(counter.allocations(), 0);
  EXPECT_EQ(updated + skipped, 10000);
  EXPECT_GT(skipped, 800);
  EXPECT_TRUE(std::isfinite(sink));
  // 2 % gross outliers do not pull the Cauchy estimate away.
  EXPECT_LT((est.parameters() - Eigen::Vector4d(-1.5, 0.7, 1.0, 0.5)).norm(), 0.05);
}

}  // namespace
}  // namespace ident
