// RecursiveLeastSquares::Update on hostile samples: the state stays finite with D positive, or the
// step is reported as rejected and leaves the state untouched (findings of fuzz/rls_fuzzer).
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <random>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Cholesky>
#include <Eigen/Core>

#include "ident/regression/rls.h"
#include "tests/support/alloc_counter.h"

namespace ident {
namespace {

struct Snapshot {
  double nu;
  Eigen::VectorXd d;
  Eigen::MatrixXd L;
  bool operator==(const Snapshot&) const = default;
};
Snapshot Take(const RecursiveLeastSquares& r) {
  return {r.nu(), r.statistics().factor().d(), r.statistics().factor().L()};
}
bool Healthy(const RecursiveLeastSquares& r) {
  const auto& d = r.statistics().factor().d();
  return d.allFinite() && d.minCoeff() >= std::numeric_limits<double>::min() &&
         r.statistics().factor().L().allFinite() && r.parameters().allFinite();
}

// Noise-free data y = θ'z from a seeded Gaussian regressor stream.
void FeedExact(RecursiveLeastSquares& rls, const Eigen::Vector2d& theta, int count, std::mt19937& rng) {
  std::normal_distribution<double> n01;
  for (int t = 0; t < count; ++t) {
    const Eigen::Vector2d z(n01(rng), n01(rng));
    ASSERT_TRUE(rls.Update(theta.dot(z), z).updated()) << t;
  }
}

// With λ = 0.5 and no excitation every d_i halves per step; unchecked it underflowed to 0 after
// ~1075 steps (fuzz finding). Now, once d would fall below kWindupFloor, steps are taken without
// forgetting: every step is still taken and d stays far above underflow.
TEST(RlsStepHealth, ForgettingWithoutExcitationNeitherUnderflowsNorFreezes) {
  std::mt19937 rng(11);
  const Eigen::Vector2d theta(0.7, -1.3);
  RlsOptions options;
  options.forgetting.factor = 0.5;
  RecursiveLeastSquares rls(2, options);
  FeedExact(rls, theta, 20, rng);
  for (int t = 0; t < 3000; ++t) {
    ASSERT_TRUE(rls.Update(0.0, Eigen::Vector2d::Zero()).updated()) << t;
    ASSERT_TRUE(Healthy(rls)) << t;
  }
  // d ∝ 0.5^t reaches 2^-900 after ~900 steps, then shrinks only as ν/(ν+1): ≈ 2^-900·3/2100.
  EXPECT_GT(rls.statistics().factor().d().minCoeff(), 1e-275);
  EXPECT_LT(rls.statistics().factor().d().minCoeff(), 1e-270);
  // Excitation returns: every step is taken again and θ̂ is the exponentially weighted least-squares
  // solution argmin Σ_k λ^(N−k) (y_k − θ'z_k)² over the new samples (the frozen past weighs < 0.5^60),
  // computed densely as a closed-form reference.
  std::normal_distribution<double> n01;
  Eigen::Matrix2d A = Eigen::Matrix2d::Zero();
  Eigen::Vector2d b = Eigen::Vector2d::Zero();
  for (int t = 0; t < 60; ++t) {
    const Eigen::Vector2d z(n01(rng), n01(rng));
    const double y = theta.dot(z) + 1e-3 * n01(rng);
    ASSERT_TRUE(rls.Update(y, z).updated()) << t;
    A = 0.5 * A + z * z.transpose();
    b = 0.5 * b + z * y;
  }
  const Eigen::Vector2d reference = A.ldlt().solve(b);
  EXPECT_NEAR(rls.parameters()(0), reference(0), 1e-9);
  EXPECT_NEAR(rls.parameters()(1), reference(1), 1e-9);
}

// Samples of wildly mixed scales (1e-130 next to 1e145, from the fuzz reproducer) overflowed the
// rank-one update's workspace and left d = inf/NaN. Every step must now leave a finite state.
TEST(RlsStepHealth, MixedScaleSamplesNeverLeaveANonFiniteState) {
  std::mt19937 rng(5);
  RlsOptions options;
  options.forgetting.factor = 0.5;
  RecursiveLeastSquares rls(3, options);
  std::normal_distribution<double> n01;
  std::uniform_int_distribution<int> exponent(-300, 150);
  int failures = 0;
  for (int t = 0; t < 2000; ++t) {
    Eigen::Vector3d z;
    for (int i = 0; i < 3; ++i) z(i) = n01(rng) * std::pow(10.0, exponent(rng));
    const double y = n01(rng) * std::pow(10.0, exponent(rng));
    const Snapshot before = Take(rls);
    const StepReport r = rls.Update(y, z);
    ASSERT_TRUE(Healthy(rls)) << t;
    if (!r.updated()) {
      ASSERT_TRUE(Take(rls) == before) << t;
      ++failures;
    }
  }
  EXPECT_LT(failures, 2000);  // it keeps estimating: most steps go through
}

TEST(RlsStepHealth, SamplesNearOverflowAreRejectedAsInvalidAndChangeNothing) {
  RecursiveLeastSquares rls(2);
  rls.Update(1.0, Eigen::Vector2d(1, 0));
  const Snapshot before = Take(rls);
  for (const double big : {1e308, -1.7976931348623157e308, 1e200}) {
    EXPECT_EQ(rls.Update(big, Eigen::Vector2d(1, 1)).status, StepStatus::kRejectedInvalid) << big;
    EXPECT_EQ(rls.Update(1.0, Eigen::Vector2d(big, 1)).status, StepStatus::kRejectedInvalid) << big;
  }
  EXPECT_EQ(rls.Update(std::nan(""), Eigen::Vector2d(1, 1)).status, StepStatus::kRejectedInvalid);
  EXPECT_EQ(rls.Update(1.0, Eigen::Vector2d(std::numeric_limits<double>::infinity(), 1)).status,
            StepStatus::kRejectedInvalid);
  EXPECT_EQ(rls.Update(1.0, Eigen::Vector3d(1, 1, 1)).status, StepStatus::kRejectedInvalid);
  EXPECT_TRUE(Take(rls) == before);
}

// Values near 1e154 (squares near 1e308) are still representable: the estimate must be exact, not
// inf/NaN. y = 3·z with z ~ 1e150: θ̂ = 3.
TEST(RlsStepHealth, LargeButRepresentableSamplesGiveTheCorrectEstimate) {
  RecursiveLeastSquares rls(1);
  for (int t = 1; t <= 20; ++t) {
    const double z = 1e150 * (1 + 0.1 * t);
    ASSERT_TRUE(rls.Update(3 * z, Eigen::Matrix<double, 1, 1>(z)).updated()) << t;
  }
  EXPECT_NEAR(rls.parameters()(0), 3.0, 1e-12);
}

// The safeguards (state copy, health check, rollback) allocate nothing: replay of the fuzz
// reproducer (ρ = 3, λ = 0.5, raw doubles of mixed scales), which exercises the rollback.
TEST(RlsStepHealth, SafeguardedStepsAllocateNothing) {
  std::ifstream in("fuzz/corpus/rls_fuzzer/crash-mixed-scales-d-not-positive", std::ios::binary);
  const std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  ASSERT_GT(bytes.size(), 3u);
  ASSERT_EQ(bytes[0] % 6, 2);  // ρ = 3
  ASSERT_EQ(bytes[1] % 6, 4);  // λ = 0.5
  RlsOptions options;
  options.forgetting.factor = 0.5;
  RecursiveLeastSquares rls(3, options);
  std::vector<double> values((bytes.size() - 3) / 8);
  std::memcpy(values.data(), bytes.data() + 3, values.size() * 8);
  int failures = 0, updates = 0;
  Eigen::Vector3d z;
  testing::AllocationCounter counter;
  for (std::size_t k = 0; k + 4 <= values.size(); k += 4) {
    z << values[k + 1], values[k + 2], values[k + 3];
    const StepReport r = rls.Update(values[k], z);
    failures += r.status == StepStatus::kNumericalFailure;
    updates += r.updated();
  }
  EXPECT_EQ(counter.allocations(), 0);
  EXPECT_GT(updates, 0);
  EXPECT_GT(failures, 0);  // the rollback path ran
  EXPECT_TRUE(Healthy(rls));
}

}  // namespace
}  // namespace ident
