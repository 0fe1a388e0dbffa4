// The O(ρ) step guard (ident/regression/internal/step_guard.h, run by ident/regression/internal/step_driver.h) decides
// exactly as the straightforward guard it replaces — copy the statistics, take the step, check every d_i ≥ DBL_MIN and
// L, Θ̂ finite, restore if not — on samples of wildly mixed scales; and the Student-t/Cauchy estimator, now guarded the
// same way, stays healthy on the fuzz reproducers (d not positive after mixed scales; a data-driven start-up prior that
// underflowed).
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <random>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Core>

#include "ident/regression/internal/extended_information.h"
#include "ident/regression/rls.h"
#include "ident/regression/student_regression.h"
#include "tests/support/alloc_counter.h"

namespace ident {
namespace {

template <class Stats>
bool Healthy(const Stats& s) {
  const auto& d = s.factor().d();
  return std::isfinite(s.nu()) && s.nu() > 0 && d.allFinite() && d.minCoeff() >= std::numeric_limits<double>::min() &&
         s.factor().L().allFinite() && s.parameters().allFinite();
}

bool SameBits(const ExtendedInformation<>& a, const ExtendedInformation<>& b) {
  const auto& fa = a.factor();
  const auto& fb = b.factor();
  const double na = a.nu(), nb = b.nu();
  return std::memcmp(fa.L().data(), fb.L().data(), sizeof(double) * fa.L().size()) == 0 &&
         std::memcmp(fa.d().data(), fb.d().data(), sizeof(double) * fa.d().size()) == 0 &&
         std::memcmp(&na, &nb, sizeof na) == 0;
}

// RLS without forgetting against the copy-step-check-restore reference, on random samples whose
// entries range over 10^-300 … 10^150: the same verdict at every step and bit-identical states.
TEST(StepGuard, DecidesExactlyAsCopyStepCheckRestore) {
  std::mt19937 rng(41);
  std::normal_distribution<double> n01;
  std::uniform_int_distribution<int> exponent(-300, 150);
  int failures = 0, steps = 0;
  for (int rho = 1; rho <= 6; ++rho) {
    RecursiveLeastSquares rls(rho);
    ExtendedInformation<> reference(RegressionPrior::Flat(rho));
    Eigen::VectorXd z(rho);
    for (int t = 0; t < 1500; ++t) {
      // Mostly ordinary samples, with bursts of mixed scales.
      const bool wild = (t / 50) % 2 == 1;
      for (int i = 0; i < rho; ++i) z(i) = n01(rng) * (wild ? std::pow(10.0, exponent(rng)) : 1.0);
      const double y = n01(rng) * (wild ? std::pow(10.0, exponent(rng)) : 1.0);
      if (!std::isfinite(y * y + z.squaredNorm())) continue;
      const StepReport r = rls.Update(y, z);
      // Reference: copy, step, full check, restore.
      const ExtendedInformation<> saved = reference;
      reference.ForgetExponential(1.0);
      const double nu = reference.nu() + 1;
      reference.Prepare(y, z);
      reference.Apply(1 / nu, nu);
      const bool ok = Healthy(reference);
      if (!ok) reference = saved;
      ASSERT_EQ(r.updated(), ok) << "rho = " << rho << ", t = " << t;
      ASSERT_TRUE(SameBits(rls.statistics(), reference)) << "rho = " << rho << ", t = " << t;
      failures += !ok;
      ++steps;
    }
  }
  std::printf("guard: %d of %d steps rejected as numerical failures\n", failures, steps);
  EXPECT_GT(failures, 0);          // the rejection path ran
  EXPECT_LT(failures, steps / 2);  // and most steps went through
}

// The bound behind the fast verdict is an upper bound on max|L_ij| after every committed step.
TEST(StepGuard, OffDiagonalBoundStaysAboveTheLargestEntry) {
  std::mt19937 rng(42);
  std::normal_distribution<double> n01;
  RlsOptions o;
  o.forgetting.factor = 0.95;
  RecursiveLeastSquares rls(5, o);
  Eigen::VectorXd z(5);
  for (int t = 0; t < 3000; ++t) {
    for (int i = 0; i < 5; ++i) z(i) = n01(rng) * (i == 2 ? 1e3 : 1.0);
    ASSERT_TRUE(rls.Update(n01(rng), z).updated());
    const auto& f = rls.statistics().factor();
    double max_abs = 0;
    for (int j = 1; j < 6; ++j) max_abs = std::max(max_abs, f.L().row(j).head(j).cwiseAbs().maxCoeff());
    ASSERT_GE(f.OffDiagonalBound(), max_abs) << t;
  }
}

// Replays a student_fuzzer input (ρ, k, λ, flags, then raw doubles) through StudentRegression.
struct Replay {
  int updates = 0, failures = 0, rejected = 0;
  bool healthy = true;
};
Replay ReplayStudent(const std::string& path, StudentRegressionOptions* used = nullptr) {
  std::ifstream in(path, std::ios::binary);
  const std::vector<unsigned char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_GT(bytes.size(), 4u) << path;
  const int rho = 1 + bytes[0] % 6;
  static constexpr double kDofs[] = {1.0, 3.0, 0.5, 30.0};
  static constexpr double kFactors[] = {1.0, 0.999, 0.99, 0.9, 0.5, 1e-3};
  StudentRegressionOptions o;
  o.dof = kDofs[bytes[1] % 4];
  o.forgetting.factor = kFactors[bytes[2] % 6];
  o.forgetting.stabilised = (bytes[3] & 1) != 0;
  o.delta = (bytes[3] & 2) ? 0 : 1;
  if (bytes[3] & 4) o.prior = RegressionPrior::Diagonal(rho, rho + 4.0, 1.0, 1e-3);
  if (used) *used = o;
  StudentRegression est(rho, o);
  std::vector<double> values((bytes.size() - 4) / 8);
  std::memcpy(values.data(), bytes.data() + 4, values.size() * 8);
  Replay r;
  Eigen::VectorXd z(rho);
  for (std::size_t k = 0; k + rho + 1 <= values.size(); k += rho + 1) {
    for (int i = 0; i < rho; ++i) z(i) = values[k + 1 + i];
    const StepReport s = est.Update(values[k], z);
    r.updates += s.updated();
    r.failures += s.status == StepStatus::kNumericalFailure;
    r.rejected += s.status == StepStatus::kRejectedInvalid;
    r.healthy = r.healthy && Healthy(est.statistics());
  }
  return r;
}

// The reproducer (Cauchy, λ = 0.999, δ = 0, mixed scales): unguarded, d went non-positive after 255
// executions; now every step leaves a healthy state or is undone.
TEST(StudentStepHealth, MixedScaleReproducerLeavesAHealthyState) {
  StudentRegressionOptions o;
  const Replay r = ReplayStudent("fuzz/corpus/student_fuzzer/crash-cauchy-mixed-scales-d-not-positive", &o);
  EXPECT_EQ(o.dof, 1.0);
  EXPECT_EQ(o.forgetting.factor, 0.999);
  EXPECT_EQ(o.delta, 0);
  EXPECT_TRUE(r.healthy);
  EXPECT_GT(r.updates, 0);
  std::printf("reproducer: %d updated, %d numerical failures, %d invalid\n", r.updates, r.failures, r.rejected);
}

// Samples of size ~1e-150: the data-driven start-up prior would have V(0) entries s² ~ 1e-300/100
// (subnormal); the restart is skipped and the estimator continues, healthy, from the provisional prior.
// Samples of size ~1e155 (s² overflows): the same.
TEST(StudentStepHealth, DataDrivenPriorOutsideTheNormalRangeIsNotUsed) {
  for (const double scale : {1e-150, 1e155}) {
    std::mt19937 rng(43);
    std::normal_distribution<double> n01;
    StudentRegression est(2);
    const RegressionPrior provisional = est.prior();
    for (int t = 0; t < 200; ++t) {
      const Eigen::Vector2d z(n01(rng) * scale, n01(rng) * scale);
      const double y = 0.5 * z(0) - 0.25 * z(1) + 0.01 * n01(rng) * scale;
      est.Update(y, z);
      ASSERT_TRUE(Healthy(est.statistics())) << "scale " << scale << ", t = " << t;
    }
    // (At 1e-150 the provisional prior's steps may be refused, so the window need not fill; either way
    // no prior outside the normal range is used.)
    EXPECT_EQ(est.prior().V0, provisional.V0) << "scale " << scale << ", in start-up: " << est.in_startup();
  }
  // An ordinary scale does restart from the window's robust scales.
  std::mt19937 rng(44);
  std::normal_distribution<double> n01;
  StudentRegression est(2);
  const RegressionPrior provisional = est.prior();
  for (int t = 0; t < 40; ++t) est.Update(n01(rng), Eigen::Vector2d(n01(rng), n01(rng)));
  EXPECT_NE(est.prior().V0, provisional.V0);
}

// With forgetting and no excitation, d shrinks geometrically; as for RLS, the step is then taken
// with λ = 1, so the estimator neither underflows nor freezes.
TEST(StudentStepHealth, ForgettingWithoutExcitationNeitherUnderflowsNorFreezes) {
  std::mt19937 rng(45);
  std::normal_distribution<double> n01;
  StudentRegressionOptions o;
  o.forgetting.factor = 0.8;  // 1/(1−λ) = 5 > ν_hard = 3 (ρ = 2, Cauchy, δ = 1)
  o.prior = RegressionPrior::Diagonal(2, 4, 1, 1e-3);
  StudentRegression est(2, o);
  for (int t = 0; t < 20; ++t) {
    const Eigen::Vector2d z(n01(rng), n01(rng));
    est.Update(0.7 * z(0) - 1.3 * z(1) + 0.01 * n01(rng), z);
  }
  testing::AllocationCounter counter;
  for (int t = 0; t < 5000; ++t) {
    ASSERT_TRUE(est.Update(0.0, Eigen::Vector2d::Zero()).updated()) << t;
    ASSERT_TRUE(Healthy(est.statistics())) << t;
  }
  EXPECT_EQ(counter.allocations(), 0);
  EXPECT_GT(est.statistics().factor().d().minCoeff(), 1e-280);
}

}  // namespace
}  // namespace ident
