// Real-time loop features of RLS (fixed-size ρ = 4 and dynamic): skip/enable leave the state
// bit-identical, Reset() returns exactly to the prior, covariance at any time without allocation
// (checked against batch least squares), forgetting changed on the fly (checked against the batch
// weighted least-squares solution), and zero allocations over 10^4 mixed loop operations.
#include <cstring>
#include <random>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Cholesky>
#include <Eigen/LU>

#include "common/dense_decompositions.h"
#include "ident/regression/rls.h"
#include "tests/regression/arx_stream.h"
#include "tests/support/alloc_counter.h"

namespace ident {
namespace {

using testing::ArxData;

// Bitwise equality of the whole estimator state (factor L, D, ν, sample count).
template <class E>
bool SameRlsStateBits(const E& a, const E& b) {
  const auto& fa = a.statistics().factor();
  const auto& fb = b.statistics().factor();
  const double na = a.nu(), nb = b.nu(), sa = a.samples(), sb = b.samples();
  return fa.L().size() == fb.L().size() &&
         std::memcmp(fa.L().data(), fb.L().data(), sizeof(double) * fa.L().size()) == 0 &&
         std::memcmp(fa.d().data(), fb.d().data(), sizeof(double) * fa.d().size()) == 0 &&
         std::memcmp(&na, &nb, sizeof na) == 0 && std::memcmp(&sa, &sb, sizeof sa) == 0;
}

RlsOptions Forgetting(double lambda, bool stabilised = false) {
  RlsOptions o;
  o.forgetting = {lambda, stabilised};
  o.prior = RegressionPrior::Diagonal(4, 5, 1, 0.01);
  return o;
}

template <class E>
class RlsRealtime : public ::testing::Test {};
using RlsVariants = ::testing::Types<BasicRecursiveLeastSquares<4>, BasicRecursiveLeastSquares<Eigen::Dynamic>>;
TYPED_TEST_SUITE(RlsRealtime, RlsVariants);

TYPED_TEST(RlsRealtime, LoopOperationsAreNoexcept) {
  TypeParam rls(4);
  const Eigen::Vector4d z = Eigen::Vector4d::Ones();
  static_assert(noexcept(rls.Update(1.0, z)));
  static_assert(noexcept(rls.Skip()));
  static_assert(noexcept(rls.Reset()));
  static_assert(noexcept(rls.set_enabled(false)));
  EXPECT_EQ(rls.Skip().status, StepStatus::kSkipped);
}

TYPED_TEST(RlsRealtime, DisabledUpdatesLeaveTheStateBitIdenticalAndResumeExactly) {
  for (const bool stabilised : {false, true}) {
    const auto data = ArxData(21, 400);
    TypeParam rls(4, Forgetting(0.98, stabilised));
    TypeParam twin(4, Forgetting(0.98, stabilised));  // never sees samples 100..149
    for (int t = 0; t < 400; ++t) {
      const bool gate = t >= 100 && t < 150;
      rls.set_enabled(!gate);
      EXPECT_EQ(rls.enabled(), !gate);
      const TypeParam before = rls;
      const StepReport r = rls.Update(data[t].y, data[t].z);
      if (gate) {
        ASSERT_EQ(r.status, StepStatus::kSkipped);
        ASSERT_TRUE(SameRlsStateBits(rls, before)) << "t = " << t;
        // Read-outs keep working on the frozen state.
        ASSERT_EQ(rls.Predict(data[t].z), before.Predict(data[t].z));
      } else {
        ASSERT_TRUE(r.updated());
        twin.Update(data[t].y, data[t].z);
      }
    }
    EXPECT_TRUE(SameRlsStateBits(rls, twin)) << "stabilised = " << stabilised;
    EXPECT_EQ(rls.parameters(), twin.parameters());
  }
}

TYPED_TEST(RlsRealtime, SkippedMissingSamplesLeaveTheStateBitIdentical) {
  const auto data = ArxData(22, 300);
  TypeParam rls(4, Forgetting(0.99));
  TypeParam twin(4, Forgetting(0.99));
  for (int t = 0; t < 300; ++t) {
    const bool missing = t % 7 == 3;
    if (missing) {
      const TypeParam before = rls;
      ASSERT_EQ(rls.Skip().status, StepStatus::kSkipped);
      ASSERT_TRUE(SameRlsStateBits(rls, before));
      // A NaN sample is rejected, also without touching the state.
      ASSERT_EQ(rls.Update(std::nan(""), data[t].z).status, StepStatus::kRejectedInvalid);
      ASSERT_TRUE(SameRlsStateBits(rls, before));
    } else {
      rls.Update(data[t].y, data[t].z);
      twin.Update(data[t].y, data[t].z);
    }
  }
  EXPECT_TRUE(SameRlsStateBits(rls, twin));
}

TYPED_TEST(RlsRealtime, ResetReturnsExactlyToThePrior) {
  const auto data = ArxData(23, 200);
  TypeParam rls(4, Forgetting(0.97, true));
  const TypeParam fresh(4, Forgetting(0.97, true));
  for (int t = 0; t < 120; ++t) rls.Update(data[t].y, data[t].z);
  ASSERT_FALSE(SameRlsStateBits(rls, fresh));
  rls.Reset();
  EXPECT_TRUE(SameRlsStateBits(rls, fresh));
  // The prior guess Θ̂(0) = V_z⁻¹V_zy = 0 for a diagonal V0.
  EXPECT_EQ(rls.parameters(), Eigen::Vector4d::Zero());
  TypeParam again(4, Forgetting(0.97, true));
  for (int t = 120; t < 200; ++t) {
    rls.Update(data[t].y, data[t].z);
    again.Update(data[t].y, data[t].z);
  }
  EXPECT_TRUE(SameRlsStateBits(rls, again));
}

// Without forgetting and with the flat prior, Θ̂ and Cov(Θ̂) are the batch least-squares ones:
// Θ̂ = (Z'Z)⁻¹Z'y,  Cov = s²(Z'Z)⁻¹,  s² = |y − ZΘ̂|²/(N − ρ).
TYPED_TEST(RlsRealtime, CovarianceAtAnyTimeEqualsBatchLeastSquares) {
  const auto data = ArxData(24, 500);
  TypeParam rls(4);
  Eigen::Matrix4d P;
  for (int N = 1; N <= 500; ++N) {
    rls.Update(data[N - 1].y, data[N - 1].z);
    if (N != 8 && N != 60 && N != 500) continue;
    Eigen::MatrixXd Z(N, 4);
    Eigen::VectorXd y(N);
    for (int t = 0; t < N; ++t) Z.row(t) = data[t].z.transpose(), y(t) = data[t].y;
    const Eigen::LDLT<Eigen::MatrixXd> ldlt = dense::Ldlt(Z.transpose() * Z);
    const Eigen::VectorXd theta = ldlt.solve(Z.transpose() * y);
    const double s2 = (y - Z * theta).squaredNorm() / (N - 4);
    const Eigen::MatrixXd cov = s2 * ldlt.solve(Eigen::MatrixXd::Identity(4, 4));
    rls.CovarianceInto(P);
    EXPECT_LT((P - cov).norm(), 1e-7 * cov.norm()) << "N = " << N;
    EXPECT_LT((P - rls.covariance()).norm(), 1e-12 * cov.norm()) << "N = " << N;
    EXPECT_EQ(P, P.transpose());
  }
}

TYPED_TEST(RlsRealtime, CovarianceIsNanUntilMoreSamplesThanParameters) {
  TypeParam rls(4);
  Eigen::Matrix4d P;
  const auto data = ArxData(25, 4);
  for (const auto& s : data) rls.Update(s.y, s.z);
  rls.CovarianceInto(P);
  EXPECT_TRUE(P.array().isNaN().all());
}

TYPED_TEST(RlsRealtime, CovarianceIntoRejectsAWrongSizeNamingIt) {
  TypeParam rls(4);
  Eigen::Matrix3d P;
  try {
    rls.CovarianceInto(P);
    FAIL() << "expected InvalidArgument";
  } catch (const InvalidArgument& e) {
    EXPECT_STREQ(e.what(), "covariance output is 3x3; need 4x4");
  }
}

// Forgetting changed on the fly: λ_t for step t. The unnormalised information after N steps is
// Σ_t w_t h_t h_t' + (Π λ) ν0 V0 with w_t = Π_{s>t} λ_s, so Θ̂ is the weighted least-squares solution
// with prior information (Π λ) ν0 V0 — solved here directly.
TYPED_TEST(RlsRealtime, ForgettingChangedOnTheFlyEqualsWeightedBatchLeastSquares) {
  const auto data = ArxData(26, 600);
  RlsOptions o = Forgetting(1.0);
  TypeParam rls(4, o);
  std::vector<double> lambda(600);
  for (int t = 0; t < 600; ++t) {
    lambda[t] = t < 200 ? 1.0 : t < 400 ? 0.95 : 0.99;
    rls.set_forgetting(lambda[t]);
    EXPECT_EQ(rls.options().forgetting.factor, lambda[t]);
    rls.Update(data[t].y, data[t].z);
  }
  Eigen::MatrixXd info = Eigen::MatrixXd::Zero(5, 5);
  double weight = 1;
  for (int t = 599; t >= 0; --t) {
    Eigen::VectorXd h(5);
    h << data[t].y, data[t].z;
    info += weight * h * h.transpose();
    weight *= lambda[t];
  }
  info += weight * o.prior->nu0 * o.prior->V0;
  const Eigen::VectorXd theta = dense::Ldlt(info.bottomRightCorner(4, 4)).solve(info.bottomLeftCorner(4, 1));
  EXPECT_LT((rls.parameters() - theta).norm(), 1e-10 * theta.norm());
  EXPECT_THROW(rls.set_forgetting(1.5), InvalidArgument);
  EXPECT_EQ(rls.options().forgetting.factor, 0.99);  // unchanged by the rejected value
}

TYPED_TEST(RlsRealtime, TenThousandLoopIterationsAllocateNothing) {
  const auto data = ArxData(27, 10000);
  TypeParam rls(4, Forgetting(0.99, true));
  Eigen::Matrix4d P;
  int updated = 0, skipped = 0;
  double sink = 0;
  testing::AllocationCounter counter;
  for (int t = 0; t < 10000; ++t) {
    rls.set_enabled(t % 500 < 480);
    if (t % 1000 == 10) rls.set_forgetting(t % 2000 == 10 ? 0.98 : 0.995);
    const StepReport r = t % 11 == 5 ? rls.Skip() : rls.Update(data[t].y, data[t].z);
    updated += r.updated();
    skipped += r.status == StepStatus::kSkipped;
    rls.CovarianceInto(P);
    sink += rls.parameters()(0) + rls.Predict(data[t].z) + (t % 5000 > 10 ? P(0, 0) : 0.0);  // NaN while n ≤ ρ
    if (t == 5000) rls.Reset();
  }
  EXPECT_EQ(counter.allocations(), 0);
  const Eigen::MatrixXd allocating = rls.covariance();  // the counter is live: this one allocates
  EXPECT_GT(counter.allocations(), 0);
  EXPECT_EQ(updated + skipped, 10000);
  EXPECT_GT(skipped, 800);
  EXPECT_TRUE(std::isfinite(sink));
  EXPECT_LT((rls.parameters() - Eigen::Vector4d(-1.5, 0.7, 1.0, 0.5)).norm(), 0.05);
}

}  // namespace
}  // namespace ident

namespace ident {
namespace {

// The allocation-free V_z⁻¹ (ExtendedInformation::ScaledVzInverse) equals the allocating one and the
// inverse of the reconstructed V_z, for ρ = 1…8 and random SPD priors.
TEST(ExtendedInformation, AllocationFreeVzInverseEqualsTheDirectInverse) {
  std::mt19937 rng(28);
  std::normal_distribution<double> g;
  for (int rho = 1; rho <= 8; ++rho) {
    Eigen::MatrixXd X(rho + 1, 3 * (rho + 1));
    for (auto& v : X.reshaped()) v = g(rng);
    RegressionPrior prior;
    prior.nu0 = 3;
    prior.V0 = X * X.transpose() / X.cols() + 0.1 * Eigen::MatrixXd::Identity(rho + 1, rho + 1);
    const ExtendedInformation<> stats(prior);
    Eigen::MatrixXd out(rho, rho);
    stats.ScaledVzInverse(2.5, out);
    const Eigen::MatrixXd direct = 2.5 * prior.V0.bottomRightCorner(rho, rho).inverse();
    EXPECT_LT((out - direct).norm(), 1e-10 * direct.norm()) << "rho = " << rho;
    EXPECT_LT((out - 2.5 * stats.VzInverse()).norm(), 1e-12 * direct.norm()) << "rho = " << rho;
  }
}

}  // namespace
}  // namespace ident
