// Lock-in of the Cauchy estimator and the safeguards of SafeStudentRegression (issue 3 item 6):
// LockInMonitor against a brute-force window median, RobustScale and RegressionPrior::FromWindow against
// hand values and the spec §8 recipe, the start-up and restart states against the plain recursion rebuilt
// independently from the same prior, and the lock-in itself on seeded ARX data with innovation outliers.
#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "ident/lock_in_monitor.h"
#include "ident/regression_prior.h"
#include "ident/rls.h"
#include "ident/safe_student_regression.h"
#include "ident/student_regression.h"
#include "tests/kh/lock_in_data.h"
#include "tests/support/alloc_counter.h"

namespace ident {
namespace {

const Eigen::Vector4d& kTheta = testing::kLockInTheta;
using Arx = testing::LockInArx;

Arx Simulate(unsigned seed, int n, double outlier_rate = 0.1) { return testing::SimulateLockInArx(seed, n, outlier_rate); }

double MedianOf(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

struct RunResult {
  double error = 0;
  double median_weight = 0;  // median νβ over the second half
};

template <class E>
RunResult RunOn(E& est, const Arx& d) {
  std::vector<double> w;
  const int n = static_cast<int>(d.y.size());
  for (int t = 0; t < n; ++t) {
    const StepReport r = est.Update(d.y[t], d.z[t]);
    if (t >= n / 2) w.push_back(r.nu * r.weight);
  }
  return {(est.parameters() - kTheta).norm(), MedianOf(w)};
}

SafeStudentOptions WithPrior(double vy0) {
  SafeStudentOptions o;  // Cauchy, δ = 1
  o.base.prior = RegressionPrior::Diagonal(4, 4 + 1 + 1, vy0, 1e-3);
  return o;
}

TEST(LockInMonitor, AgreesWithTheMedianOfTheLastWindowWeights) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> uni(0, 1);
  const int M = 31;
  LockInMonitor monitor(M, 0.3);
  std::vector<double> history;
  int flags = 0;
  for (int t = 0; t < 3000; ++t) {
    // Regimes of mostly high and mostly low weights, so that both answers occur.
    const double p_low = (t / 300) % 2 ? 0.8 : 0.2;
    const double w = uni(rng) < p_low ? 0.3 * uni(rng) * 0.999 : 0.3 + 2 * uni(rng);
    history.push_back(w);
    const bool flagged = monitor.Add(w);
    bool expected = false;
    if (t + 1 >= M) {  // brute force: the median of the last M weights is below the threshold
      expected = MedianOf(std::vector<double>(history.end() - M, history.end())) < 0.3;
      EXPECT_NEAR(monitor.low_fraction(),
                  std::count_if(history.end() - M, history.end(), [](double v) { return v < 0.3; }) / double(M),
                  1e-15);
    }
    ASSERT_EQ(flagged, expected) << t;
    flags += flagged;
  }
  EXPECT_GT(flags, 500);
  EXPECT_LT(flags, 2500);
  EXPECT_TRUE(LockInMonitor(2, 1).Add(NAN) == false);  // not full yet
  EXPECT_THROW(LockInMonitor(1, 0.3), InvalidArgument);
  EXPECT_THROW(LockInMonitor(10, 0), InvalidArgument);
}

TEST(RobustScale, IsTheScaledMedianAbsoluteDeviation) {
  EXPECT_DOUBLE_EQ(RobustScale(Eigen::Vector<double, 5>(1, 2, 3, 4, 100)), 1.4826);  // median 3, MAD 1
  EXPECT_DOUBLE_EQ(RobustScale(Eigen::Vector3d(2, 2, 2)), 2.0);                      // MAD 0: RMS
  EXPECT_DOUBLE_EQ(RobustScale(Eigen::Vector3d(0, 0, 0)), 1.0);
  std::mt19937_64 rng(3);
  std::normal_distribution<double> g(5, 0.7);
  Eigen::VectorXd x(20000);
  for (auto& v : x) v = g(rng);
  EXPECT_NEAR(RobustScale(x.tail(12000)), 0.7, 0.02);
  // 40 % gross one-sided outliers: the median moves to the 5/6 quantile of the good data and the MAD
  // stays O(σ) (the RMS would be ~6e5).
  for (int i = 0; i < 8000; ++i) x(i) = 1e6;
  EXPECT_GT(RobustScale(x), 0.7);
  EXPECT_LT(RobustScale(x), 0.7 * 4);
}

TEST(RegressionPriorFromWindow, IsTheSpecRecipeWithRobustScales) {
  std::mt19937_64 rng(5);
  std::normal_distribution<double> g;
  Eigen::MatrixXd window(25, 4);
  for (int i = 0; i < 25; ++i) window.row(i) << 3 * g(rng), g(rng), 0.01 * g(rng), 100 + 7 * g(rng);
  const double sy = RobustScale(window.col(0));
  Eigen::MatrixXd P0 = Eigen::MatrixXd::Zero(3, 3);
  for (int i = 0; i < 3; ++i) P0(i, i) = std::pow(10 * sy / RobustScale(window.col(i + 1)), 2);
  for (double sigma0 : {0.0, 0.37}) {
    const RegressionPrior p = RegressionPrior::FromWindow(window, 5.5, 1, sigma0);
    const RegressionPrior q = RegressionPrior::FromGuess(Eigen::Vector3d::Zero(), P0, sigma0 > 0 ? sigma0 : sy, 5.5, 1);
    EXPECT_EQ(p.nu0, 5.5);
    EXPECT_LT((p.V0 - q.V0).norm(), 1e-13 * q.V0.norm()) << p.V0 << "\n" << q.V0;
  }
  EXPECT_THROW(RegressionPrior::FromWindow(window, 4, 1), InvalidArgument);  // ν0 ≤ ρ+δ
  EXPECT_THROW(RegressionPrior::FromWindow(window.topRows(1), 6, 1), InvalidArgument);
  EXPECT_THROW(RegressionPrior::FromWindow(window, 6, 1, -1), InvalidArgument);
}

// The paper's exact recursion with a too small prior scale D_y(0) locks into a wrong mode on the
// study's data; the lock-in monitor flags it and the restart recovers (examples/kh_outlier_study).
TEST(SafeStudentRegression, RecoversFromTheCauchyLockIn) {
  int locked = 0;
  for (unsigned seed = 1000; seed < 1010; ++seed) {
    const Arx d = Simulate(seed, 2000);
    SafeStudentOptions exact = WithPrior(1e-6);
    exact.base.exact = true;
    SafeStudentRegression plain(4, exact), safe(4, WithPrior(1e-6));
    const RunResult before = RunOn(plain, d), after = RunOn(safe, d);
    RecursiveLeastSquares rls(4);  // reference scale of the error: RLS on this record without outliers
    const RunResult clean = RunOn(rls, Simulate(seed, 2000, 0.0));
    if (before.error > 0.3 && before.median_weight < 0.3) {
      ++locked;
      EXPECT_GE(safe.restarts(), 1) << seed;
      EXPECT_LT(after.error, 4 * clean.error) << seed;
      EXPECT_GT(after.median_weight, 0.5) << seed;
    }
    EXPECT_EQ(plain.lock_ins(), 0);  // exact: no monitor
  }
  EXPECT_GE(locked, 2);  // the mechanism is reproduced (76 of 200 runs in the study)
}

// A restart is the plain recursion from the data-driven prior of the replayed samples: rebuild it
// independently from the buffered samples and compare.
TEST(SafeStudentRegression, RestartIsTheExactRecursionFromTheRobustPriorOfTheRecentSamples) {
  const Arx d = Simulate(1000, 1500);
  SafeStudentOptions o = WithPrior(1e-6);
  SafeStudentRegression safe(4, o);
  const int R = 100;  // max(W, M) for ρ = 4 with an explicit prior: M = max(100, 20ρ)
  int t = 0;
  while (safe.restarts() == 0 && t < 1500) safe.Update(d.y[t], d.z[t]), ++t;
  ASSERT_EQ(safe.restarts(), 1);
  Eigen::MatrixXd window(R, 5);
  for (int i = 0; i < R; ++i) window.row(i) << d.y[t - R + i], d.z[t - R + i].transpose();
  auto replay = [&](const RegressionPrior& prior) {
    StudentRegressionOptions so;
    so.prior = prior;
    StudentRegression est(4, so);
    for (int i = 0; i < R; ++i) est.Update(window(i, 0), window.row(i).tail(4).transpose());
    return est;
  };
  const StudentRegression first = replay(RegressionPrior::FromWindow(window, 6, 1));
  const Eigen::VectorXd residuals = window.col(0) - window.rightCols(4) * first.parameters();
  const double sigma0 = 4 * RobustScale(residuals);  // G^{(k+1)/(2k)} = 4 for k = 1
  const StudentRegression second = replay(RegressionPrior::FromWindow(window, 6, 1, sigma0));
  EXPECT_NEAR(safe.prior().V0(0, 0), sigma0 * sigma0, 1e-14 * sigma0 * sigma0);
  EXPECT_LT((safe.parameters() - second.parameters()).norm(), 1e-12 * second.parameters().norm());
  EXPECT_NEAR(safe.Dy(), second.Dy(), 1e-12 * second.Dy());
  EXPECT_EQ(safe.nu(), second.nu());
}

TEST(SafeStudentRegression, StartUpPriorFollowsTheRule) {
  const Arx d = Simulate(7, 200);
  SafeStudentOptions o;
  o.base.dof = 3;
  SafeStudentRegression safe(4, o);
  EXPECT_TRUE(safe.in_startup());
  for (int t = 0; t < 20; ++t) safe.Update(d.y[t], d.z[t]);
  EXPECT_FALSE(safe.in_startup());
  Eigen::MatrixXd window(20, 5);
  for (int i = 0; i < 20; ++i) window.row(i) << d.y[i], d.z[i].transpose();
  StudentRegressionOptions so;
  so.dof = 3;
  so.prior = RegressionPrior::FromWindow(window, 4 + 3 + 1, 1);
  StudentRegression first(4, so);
  for (int i = 0; i < 20; ++i) first.Update(d.y[i], d.z[i]);
  const double se = RobustScale(window.col(0) - window.rightCols(4) * first.parameters());
  const double G = 4, factor2 = std::pow(G, (3.0 + 1) / 3);  // σ0² = G^{(k+1)/k}·s_e²
  EXPECT_NEAR(safe.prior().V0(0, 0), factor2 * se * se, 1e-13 * factor2 * se * se);
  EXPECT_EQ(safe.prior().nu0, 8);
  // The scale of the window fit is far below s_y (which contains the signal): the point of the refinement.
  EXPECT_LT(safe.prior().V0(0, 0), 0.1 * std::pow(RobustScale(window.col(0)), 2));
  // After start-up: the plain recursion from that prior, step by step.
  so.prior = safe.prior();
  StudentRegression plain(4, so);
  for (int i = 0; i < 20; ++i) plain.Update(d.y[i], d.z[i]);
  for (int t = 20; t < 200; ++t) {
    const StepReport a = safe.Update(d.y[t], d.z[t]), b = plain.Update(d.y[t], d.z[t]);
    ASSERT_EQ(a.weight, b.weight) << t;
  }
}

TEST(SafeStudentRegression, ExactIsThePlainRecursion) {
  const Arx d = Simulate(8, 500);
  for (double dof : {1.0, 3.0}) {
    SafeStudentOptions o;
    o.base.dof = dof;
    o.base.exact = true;
    SafeStudentRegression safe(4, o);
    StudentRegression plain(4, o.base);
    for (int t = 0; t < 498; ++t) ASSERT_EQ(safe.Update(d.y[t], d.z[t]).weight, plain.Update(d.y[t], d.z[t]).weight);
    EXPECT_EQ(safe.parameters(), plain.parameters());
  }
}

TEST(SafeStudentRegression, NoRestartOnCleanOrOutlierDataWithAGoodStart) {
  for (double rate : {0.0, 0.1})
    for (double dof : {1.0, 3.0}) {
      const Arx d = Simulate(21, 5000, rate);
      SafeStudentOptions o;
      o.base.dof = dof;
      SafeStudentRegression safe(4, o);
      const RunResult r = RunOn(safe, d);
      EXPECT_EQ(safe.lock_ins(), 0) << rate << " " << dof;
      EXPECT_LT(r.error, 0.02);
    }
}

TEST(SafeStudentRegression, UpdateDoesNotAllocateBetweenRestarts) {
  const Arx d = Simulate(9, 1200);
  SafeStudentRegression safe(4);
  for (int t = 0; t < 100; ++t) safe.Update(d.y[t], d.z[t]);
  testing::AllocationCounter count;
  for (int t = 100; t < 1198; ++t) safe.Update(d.y[t], d.z[t]);
  EXPECT_EQ(count.allocations(), 0);
  EXPECT_EQ(safe.restarts(), 0);
}

TEST(SafeStudentRegression, RejectsBadOptionsNamingThem) {
  auto message = [](SafeStudentOptions o) {
    try {
      SafeStudentRegression est(4, o);
    } catch (const InvalidArgument& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  SafeStudentOptions o;
  o.scale_growth = 0.5;
  EXPECT_NE(message(o).find("scale_growth = 0.5"), std::string::npos) << message(o);
  o = {};
  o.lock_in_window = 1;
  EXPECT_NE(message(o).find("lock_in_window = 1"), std::string::npos) << message(o);
  o = {};
  o.lock_in_threshold = -1;
  EXPECT_NE(message(o).find("lock-in threshold = -1"), std::string::npos) << message(o);
  o = {};
  o.lock_in_threshold = 2;  // νβ ≤ (k+1)/k = 2 for Cauchy: every sample would count as low
  EXPECT_NE(message(o).find("lock-in threshold = 2; need 0 < threshold < (k+1)/k = 2"), std::string::npos)
      << message(o);
  o = {};
  o.startup_window = 1;
  EXPECT_NE(message(o).find("startup_window = 1"), std::string::npos) << message(o);
  o = {};
  o.base.dof = -2;
  EXPECT_NE(message(o).find("dof = -2"), std::string::npos) << message(o);
}

}  // namespace
}  // namespace ident
