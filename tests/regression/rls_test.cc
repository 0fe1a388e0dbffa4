#include "ident/regression/rls.h"

#include <random>

#include <cstdio>

#include <gtest/gtest.h>

#include "tests/support/alloc_counter.h"
#include "tests/support/dense_rls.h"

namespace ident {
namespace {

// A stable ARX(2,2) stream driven by a binary input and Gaussian noise.
struct ArxStream {
  explicit ArxStream(unsigned seed, Eigen::Vector4d theta = {-1.5, 0.7, 1.0, 0.5}) : rng(seed), theta(theta) {}
  // Returns (y, z) for the next sample.
  std::pair<double, Eigen::Vector4d> Next() {
    Eigen::Vector4d z(-y1, -y2, u1, u2);
    const double y = theta.dot(z) + 0.1 * noise(rng);
    y2 = y1;
    y1 = y;
    u2 = u1;
    u1 = coin(rng) ? 1.0 : -1.0;
    return {y, z};
  }
  std::mt19937 rng;
  Eigen::Vector4d theta;
  std::normal_distribution<double> noise;
  std::bernoulli_distribution coin;
  double y1 = 0, y2 = 0, u1 = 1, u2 = -1;
};

double RlsMaxRelativeDifference(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  return ((a - b).cwiseAbs().array() / b.cwiseAbs().array().max(1e-300)).maxCoeff();
}

TEST(RecursiveLeastSquares, LdFormEqualsDenseOracleOver100kUpdatesWithForgetting) {
  const double lambda = 0.99;
  const RegressionPrior prior = RegressionPrior::Diagonal(4, 10, 1, 1);
  RlsOptions options;
  options.forgetting.factor = lambda;
  options.prior = prior;
  RecursiveLeastSquares rls(4, options);
  DenseRls dense(prior, lambda);
  ArxStream stream(11);
  double worst_theta = 0, worst_dy = 0;
  for (int t = 0; t < 100000; ++t) {
    const auto [y, z] = stream.Next();
    ASSERT_TRUE(rls.Update(y, z).updated());
    dense.Update(y, z);
    if (t % 97 == 0 || t == 99999) {
      worst_theta = std::max(worst_theta, RlsMaxRelativeDifference(rls.parameters(), dense.parameters()));
      worst_dy = std::max(worst_dy, std::abs(rls.Dy() - dense.Dy()) / dense.Dy());
      ASSERT_GT(rls.statistics().factor().d().minCoeff(), 0) << "V lost positive definiteness at t=" << t;
    }
  }
  std::printf("[ measured ] LD vs dense over 1e5 updates: max rel. diff theta %.3g, Dy %.3g\n", worst_theta, worst_dy);
  EXPECT_LE(worst_theta, 1e-9);
  EXPECT_LE(worst_dy, 1e-9);
  EXPECT_NEAR(rls.nu(), dense.nu(), 1e-9 * dense.nu());
  // Forgetting: ν → 1/(1−λ) = 100.
  EXPECT_NEAR(rls.nu(), 1 / (1 - lambda), 1e-6);
  // V_z⁻¹/ν equals the oracle's P.
  EXPECT_LT((rls.statistics().VzInverse() / rls.nu() - dense.P()).norm(), 1e-8 * dense.P().norm());
}

TEST(RecursiveLeastSquares, ForgettingTracksAStepChangeOfTheParameters) {
  RlsOptions options;
  options.forgetting.factor = 0.95;
  RecursiveLeastSquares rls(4, options);
  ArxStream stream(12);
  for (int t = 0; t < 1000; ++t) {
    const auto [y, z] = stream.Next();
    rls.Update(y, z);
  }
  EXPECT_LT((rls.parameters() - stream.theta).norm(), 0.05);
  const Eigen::Vector4d after(-1.2, 0.5, 2.0, -0.5);
  stream.theta = after;
  double error_just_after = 0;
  for (int t = 0; t < 300; ++t) {
    const auto [y, z] = stream.Next();
    rls.Update(y, z);
    if (t == 2) error_just_after = (rls.parameters() - after).norm();
  }
  // The effective memory is 1/(1−λ) = 20 samples; 300 samples after the step the error is down to
  // the noise level, far below the jump size (|Δθ| ≈ 1.5).
  EXPECT_GT(error_just_after, 0.3);
  EXPECT_LT((rls.parameters() - after).norm(), 0.1);
  // Without forgetting the same data leave a large bias.
  RecursiveLeastSquares no_forgetting(4);
  ArxStream s2(12);
  for (int t = 0; t < 1300; ++t) {
    if (t == 1000) s2.theta = after;
    const auto [y, z] = s2.Next();
    no_forgetting.Update(y, z);
  }
  EXPECT_GT((no_forgetting.parameters() - after).norm(), 0.3);
}

TEST(RecursiveLeastSquares, UpdateAllocatesNothingAfterConstruction) {
  RlsOptions options;
  options.forgetting.factor = 0.99;
  options.forgetting.stabilised = true;
  RecursiveLeastSquares rls(4, options);
  BasicRecursiveLeastSquares<4> fixed(4, options);
  ArxStream stream(13);
  std::vector<std::pair<double, Eigen::Vector4d>> data;
  for (int t = 0; t < 10000; ++t) data.push_back(stream.Next());
  testing::AllocationCounter counter;
  double sink = 0;
  for (const auto& [y, z] : data) {
    rls.Update(y, z);
    fixed.Update(y, z);
    sink += rls.parameters()(0) + rls.Predict(z) + fixed.parameters()(1);
  }
  EXPECT_EQ(counter.allocations(), 0);
  EXPECT_TRUE(std::isfinite(sink));
  EXPECT_LT((rls.parameters() - fixed.parameters()).norm(), 1e-12);
}

TEST(RecursiveLeastSquares, StabilisedForgettingFollowsItsNuRecursion) {
  const RegressionPrior prior = RegressionPrior::Diagonal(4, 8, 1, 0.01);
  RlsOptions options;
  options.forgetting = {0.9, true};
  options.prior = prior;
  RecursiveLeastSquares rls(4, options);
  ArxStream stream(14);
  double nu = prior.nu0;
  for (int t = 0; t < 200; ++t) {
    const auto [y, z] = stream.Next();
    rls.Update(y, z);
    nu = 0.9 * nu + 0.1 * prior.nu0 + 1;
    ASSERT_NEAR(rls.nu(), nu, 1e-12 * nu);
  }
}

TEST(RecursiveLeastSquares, RejectsNonFiniteSamplesWithoutTouchingTheState) {
  RecursiveLeastSquares rls(2);
  rls.Update(1.0, Eigen::Vector2d(1, 0));
  rls.Update(2.0, Eigen::Vector2d(0, 1));
  const Eigen::VectorXd before = rls.parameters();
  const double nu = rls.nu();
  EXPECT_EQ(rls.Update(std::nan(""), Eigen::Vector2d(1, 1)).status, StepStatus::kRejectedInvalid);
  EXPECT_EQ(rls.Update(1.0, Eigen::Vector2d(1, INFINITY)).status, StepStatus::kRejectedInvalid);
  EXPECT_EQ(rls.Update(1.0, Eigen::Vector2d(1e300, 1e300)).status, StepStatus::kRejectedInvalid);
  EXPECT_EQ(rls.Update(1.0, Eigen::Vector3d(1, 1, 1)).status, StepStatus::kRejectedInvalid);
  EXPECT_EQ(rls.parameters(), before);
  EXPECT_EQ(rls.nu(), nu);
}

TEST(RecursiveLeastSquares, RejectsInvalidOptionsNamingTheOption) {
  RlsOptions options;
  options.forgetting.factor = 1.2;
  try {
    RecursiveLeastSquares rls(3, options);
    FAIL() << "expected InvalidArgument";
  } catch (const InvalidArgument& e) {
    EXPECT_STREQ(e.what(), "forgetting = 1.2; need 0 < forgetting <= 1");
  }
  options.forgetting.factor = 0;
  EXPECT_THROW(RecursiveLeastSquares(3, options), InvalidArgument);
  options.forgetting.factor = 1;
  options.prior = RegressionPrior::Diagonal(2, 5, 1, 1);
  EXPECT_THROW(RecursiveLeastSquares(3, options), InvalidArgument);  // V0 has the wrong size
  EXPECT_THROW(RegressionPrior::Diagonal(2, -1, 1, 1), InvalidArgument);
  EXPECT_THROW(RegressionPrior::Diagonal(2, 5, -1, 1), InvalidArgument);
}

}  // namespace
}  // namespace ident
