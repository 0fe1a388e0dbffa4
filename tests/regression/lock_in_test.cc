// Lock-in of the Cauchy estimator and the safeguards of SafeStudentRegression:
// LockInMonitor against a brute-force window median, RobustScale and RegressionPrior::FromWindow against
// hand values and the spec §8 recipe, the start-up and restart states against the plain recursion rebuilt
// independently from the same prior, and the lock-in itself on seeded ARX data with innovation outliers.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "ident/regression/batch_regression.h"
#include "ident/regression/internal/lagged_output_screen.h"
#include "ident/regression/lock_in_monitor.h"
#include "ident/regression/regression_prior.h"
#include "ident/regression/rls.h"
#include "ident/regression/safe_student_regression.h"
#include "ident/regression/student_regression.h"
#include "tests/regression/lock_in_data.h"
#include "tests/support/alloc_counter.h"

namespace ident {
namespace {

const Eigen::Vector4d& kTheta = testing::kLockInTheta;
using Arx = testing::LockInArx;

Arx Simulate(unsigned seed, int n, double outlier_rate = 0.1) {
  return testing::SimulateLockInArx(seed, n, outlier_rate);
}

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
                  std::count_if(history.end() - M, history.end(), [](double v) { return v < 0.3; }) / double(M), 1e-15);
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

// FromWindow is spec §8's recipe with Θ0 given, σ0 and P0 = (10·s_y)²·M⁻¹, M = Z'Z/n (rebuilt through
// FromGuess), and it is equivariant: y → c·y + b'z, z → T·z, Θ0 → T⁻ᵀ(cΘ0 + b) transforms V(0) into
// M V(0) M' with M = [[c, b'], [0, T]] (spec §10.8) — what keeps an uncentred regressor next to an
// intercept from meeting a prior that pulls the intercept to 0.
TEST(RegressionPriorFromWindow, IsTheSpecRecipeAndEquivariant) {
  std::mt19937_64 rng(5);
  std::normal_distribution<double> g;
  Eigen::MatrixXd window(25, 4);
  for (int i = 0; i < 25; ++i) window.row(i) << 3 * g(rng), g(rng), 0.01 * g(rng), 100 + 7 * g(rng);
  const Eigen::MatrixXd Z = window.rightCols(3);
  const Eigen::MatrixXd M = Z.transpose() * Z / 25.0 * (1 + 1e-9);  // the documented regularisation
  const double sy = RobustScale(window.col(0));
  const Eigen::Vector3d theta0(0.5, -2, 0.03);
  for (double sigma0 : {0.0, 0.37}) {
    const RegressionPrior p = RegressionPrior::FromWindow(window, 5.5, 1, sigma0, theta0);
    const Eigen::MatrixXd P0 = 100 * sy * sy * M.inverse();
    const RegressionPrior q = RegressionPrior::FromGuess(theta0, P0, sigma0 > 0 ? sigma0 : sy, 5.5, 1);
    EXPECT_EQ(p.nu0, 5.5);
    EXPECT_LT((p.V0 - q.V0).norm(), 1e-9 * q.V0.norm()) << p.V0 << "\n" << q.V0;
  }
  // Equivariance (σ0 = 0: s_y of the transformed window; b = 0 keeps the MAD's median-based scale exact).
  Eigen::Matrix4d T = Eigen::Matrix4d::Zero();
  T(0, 0) = -3;
  T.bottomRightCorner(3, 3) << 2, 0, 0, 0.5, 1, 0, 1, 0, 4;  // mixes an uncentred column into the others
  const Eigen::MatrixXd moved = window * T.transpose();
  const Eigen::Vector3d moved_theta0 = T.bottomRightCorner(3, 3).transpose().inverse() * (-3 * theta0);
  const RegressionPrior a = RegressionPrior::FromWindow(window, 6, 1, 0, theta0);
  const RegressionPrior b = RegressionPrior::FromWindow(moved, 6, 1, 0, moved_theta0);
  const Eigen::MatrixXd expected = T * a.V0 * T.transpose();
  EXPECT_LT((b.V0 - expected).norm(), 1e-9 * expected.norm());
  EXPECT_THROW(RegressionPrior::FromWindow(window, 4, 1), InvalidArgument);  // ν0 ≤ ρ+δ
  EXPECT_THROW(RegressionPrior::FromWindow(window.topRows(1), 6, 1), InvalidArgument);
  EXPECT_THROW(RegressionPrior::FromWindow(window, 6, 1, -1), InvalidArgument);
  EXPECT_THROW(RegressionPrior::FromWindow(window, 6, 1, 0, Eigen::Vector2d(1, 2)), InvalidArgument);
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

// The documented robust prior of a window (ident/regression/safe_student_regression.h), rebuilt here from its
// parts: Cauchy ML of the window's rows that carry no gross output outlier (the lagged-output screen), weights
// 2/(1 + r²/γ²), M_w, σ0 = G^{(k+1)/(2k)}·RobustScale(r).
RegressionPrior RobustPriorOf(const Eigen::MatrixXd& all_rows, double nu0, double dof, double growth = 4) {
  const Eigen::Array<bool, Eigen::Dynamic, 1> poisoned = internal::ScreenLaggedOutputs(all_rows).poisoned;
  Eigen::MatrixXd window(all_rows.rows() - poisoned.count(), all_rows.cols());
  for (Eigen::Index i = 0, k = 0; i < all_rows.rows(); ++i)
    if (!poisoned(i)) window.row(k++) = all_rows.row(i);
  const Eigen::MatrixXd Z = window.rightCols(window.cols() - 1);
  const BatchRegressionResult fit = CauchyMlRegression(Z, window.col(0));
  const Eigen::VectorXd r = window.col(0) - Z * fit.theta;
  const Eigen::VectorXd w = 2 / (1 + r.array().square() / (fit.scale * fit.scale));
  Eigen::MatrixXd M = Z.transpose() * w.asDiagonal() * Z / w.sum();
  M = 0.5 * (M + M.transpose());
  const double sigma0 = std::pow(growth, (dof + 1) / (2 * dof)) * RobustScale(r);
  RegressionPrior prior{nu0, Eigen::MatrixXd(window.cols(), window.cols())};
  prior.V0.bottomRightCorner(M.rows(), M.cols()) = M;
  prior.V0.bottomLeftCorner(M.rows(), 1) = M * fit.theta;
  prior.V0.topRightCorner(1, M.rows()) = (M * fit.theta).transpose();
  prior.V0(0, 0) = sigma0 * sigma0 + fit.theta.dot(M * fit.theta);
  return prior;
}

// The plain recursion (with the leverage guard) from `prior` over rows [first, last) of `d`.
StudentRegression Replayed(const RegressionPrior& prior, const Arx& d, int first, int last, double dof = 1) {
  StudentRegressionOptions so;
  so.dof = dof;
  so.prior = prior;
  so.leverage_guard = true;
  StudentRegression est(4, so);
  est.set_outlying_regressor(false);  // the guard by the metric distance z'Ṽ_z⁻¹z alone
  for (int t = first; t < last; ++t) est.Update(d.y[t], d.z[t]);
  return est;
}

Eigen::MatrixXd WindowOf(const Arx& d, int first, int last) {
  Eigen::MatrixXd window(last - first, 5);
  for (int i = first; i < last; ++i) window.row(i - first) << d.y[i], d.z[i].transpose();
  return window;
}

// A restart is the plain recursion from the robust prior of the recent samples (ν0 = ρ+k+δ) replaying
// every sample seen: rebuilt independently and compared; ν at the end counts every update.
TEST(SafeStudentRegression, RestartReplaysEverySampleFromTheRobustPriorOfTheRecentOnes) {
  const Arx d = Simulate(1000, 1500);
  SafeStudentRegression safe(4, WithPrior(1e-6));
  const int R = 100;  // max(W, M) for ρ = 4 with an explicit prior: M = max(100, 20ρ)
  int t = 0;
  while (safe.restarts() == 0 && t < std::ssize(d.y)) safe.Update(d.y[t], d.z[t]), ++t;
  ASSERT_EQ(safe.restarts(), 1);
  const StudentRegression rebuilt = Replayed(RobustPriorOf(WindowOf(d, t - R, t), 6, 1), d, 0, t);
  EXPECT_LT((safe.parameters() - rebuilt.parameters()).norm(), 1e-12 * rebuilt.parameters().norm());
  EXPECT_NEAR(safe.Dy(), rebuilt.Dy(), 1e-12 * rebuilt.Dy());
  EXPECT_EQ(safe.nu(), 6 + t);
  const RestartEvent& e = safe.restart_events().at(0);
  EXPECT_EQ(e.update, t);
  EXPECT_EQ(e.replayed, t);
  EXPECT_EQ(e.dropped, 0);
  EXPECT_GT(e.low_weight_before, 0.5);
  EXPECT_LT(e.low_weight_after, 0.5);
  EXPECT_TRUE(e.resolved);
}

// The start-up: after W samples the estimator restarts from the robust prior of the window with
// ν0 = W and replays it, then runs the plain recursion (with the leverage guard) step by step.
TEST(SafeStudentRegression, StartUpPriorFollowsTheRule) {
  const Arx d = Simulate(7, 200);
  SafeStudentOptions o;
  o.base.dof = 3;
  SafeStudentRegression safe(4, o);
  EXPECT_TRUE(safe.in_startup());
  for (int t = 0; t < 20; ++t) safe.Update(d.y[t], d.z[t]);
  EXPECT_FALSE(safe.in_startup());
  const RegressionPrior expected = RobustPriorOf(WindowOf(d, 0, 20), 20, 3);
  EXPECT_LT((safe.prior().V0 - expected.V0).norm(), 1e-12 * expected.V0.norm());
  EXPECT_EQ(safe.prior().nu0, 20);
  StudentRegression plain = Replayed(safe.prior(), d, 0, 20, 3);
  const int n = static_cast<int>(d.y.size());  // 198 regressions from 200 samples
  for (int t = 20; t < n; ++t) {
    const StepReport a = safe.Update(d.y[t], d.z[t]), b = plain.Update(d.y[t], d.z[t]);
    ASSERT_EQ(a.weight, b.weight) << t;
  }
  EXPECT_EQ(safe.nu(), 20 + n);
}

// The start waits while the window cannot determine every coefficient from its inliers: here the second
// regressor moves at one row of the first 20 only (that row alone would decide its coefficient, and
// would be fitted exactly whatever it holds), so the start comes at the next attempt, on the last 40 rows.
TEST(SafeStudentRegression, StartWaitsUntilNoRowAloneDecidesADirection) {
  std::mt19937_64 rng(12);
  std::normal_distribution<double> g;
  SafeStudentRegression est(2);
  for (int t = 0; t < 40; ++t) {
    const Eigen::Vector2d z(g(rng), t == 7 || t >= 20 ? g(rng) : 0.0);
    const double y = z.dot(Eigen::Vector2d(1, -2)) + 0.1 * g(rng) + (t == 7 ? 50.0 : 0.0);
    est.Update(y, z);
    if (t == 19) {
      EXPECT_TRUE(est.in_startup());
    }
  }
  EXPECT_FALSE(est.in_startup());
  EXPECT_EQ(est.prior().nu0, 40);
  EXPECT_LT((est.parameters() - Eigen::Vector2d(1, -2)).norm(), 0.1);
}

// A quarter of the start-up window gross output outliers: the high-breakdown start keeps the estimate where
// the clean record's is (outliers that also enter later ARX regressors are the workflow's to clean,
// models/output_cleaner.h).
TEST(SafeStudentRegression, StartUpSurvivesGrossOutliersInTheWindow) {
  for (unsigned seed = 40; seed < 50; ++seed) {
    const Arx clean = Simulate(seed, 400, 0.0);
    Arx d = clean;
    std::mt19937_64 rng(seed);
    for (int k = 0; k < 5; ++k) d.y[4 * k + static_cast<int>(rng() % 4)] += (rng() & 1 ? 1 : -1) * 1000 * 0.1;
    SafeStudentRegression a(4), b(4);
    for (int t = 0; t < 398; ++t) a.Update(d.y[t], d.z[t]), b.Update(clean.y[t], clean.z[t]);
    EXPECT_LT((a.parameters() - kTheta).norm(), 0.05) << seed;
    EXPECT_LT((a.parameters() - b.parameters()).norm(), 0.02) << seed;
  }
}

// A second pass starts from the first pass's V with the weight of its updates and the t-scale of its
// residuals, so that the recursion weighs every sample against an estimate near the end result; on
// Cauchy-noise regressions it ends closer to the batch Cauchy ML than the single pass does.
TEST(SafeStudentRegression, PassesApproachTheBatchCauchyMaximumLikelihood) {
  std::cauchy_distribution<double> cauchy(0, 1);
  std::normal_distribution<double> g;
  double single = 0, triple = 0;
  for (unsigned seed = 0; seed < 30; ++seed) {
    std::mt19937_64 rng(seed);
    const int n = 300;
    Eigen::MatrixXd Z(n, 3);
    Eigen::VectorXd y(n);
    for (int t = 0; t < n; ++t) {
      Z.row(t) << 1, g(rng), g(rng);
      y(t) = Z.row(t).dot(Eigen::Vector3d(1, 2, -1)) + cauchy(rng);
    }
    const Eigen::VectorXd ml = CauchyMlRegression(Z, y).theta;
    SafeStudentRegression est(3);
    for (int pass = 1; pass <= 3; ++pass) {
      if (pass > 1) {
        ASSERT_TRUE(est.BeginPass());
      }
      for (int t = 0; t < n; ++t) est.Update(y(t), Z.row(t).transpose());
      if (pass == 1) single += (est.parameters() - ml).norm();
    }
    triple += (est.parameters() - ml).norm();
    EXPECT_EQ(est.nu(), 2 * n);  // the pass prior carries the previous pass's n updates
  }
  std::printf("[ measured ] mean distance to batch Cauchy ML: %.4f (one pass), %.4f (three passes)\n", single / 30,
              triple / 30);
  EXPECT_LT(triple, 0.6 * single) << single / 30 << " " << triple / 30;
  SafeStudentOptions exact;
  exact.base.exact = true;
  SafeStudentRegression plain(3, exact);
  EXPECT_FALSE(plain.BeginPass());
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

// The kept history grows geometrically; sized beforehand (history_reserve) nothing allocates between
// restarts. With history_limit the oldest samples leave a ring, and a restart says how many it dropped.
TEST(SafeStudentRegression, UpdateDoesNotAllocateBetweenRestartsAndTheHistoryIsBounded) {
  const Arx d = Simulate(9, 1200);
  SafeStudentOptions o;
  o.history_reserve = 1200;
  SafeStudentRegression safe(4, o);
  for (int t = 0; t < 100; ++t) safe.Update(d.y[t], d.z[t]);
  testing::AllocationCounter count;
  for (int t = 100; t < 1198; ++t) safe.Update(d.y[t], d.z[t]);
  EXPECT_EQ(count.allocations(), 0);
  EXPECT_EQ(safe.restarts(), 0);
  EXPECT_EQ(safe.history_size(), 1198);

  SafeStudentOptions limited = WithPrior(1e-6);
  limited.history_limit = 150;
  SafeStudentRegression ring(4, limited);
  const Arx locked = Simulate(1000, 1500);
  for (int t = 0; t < std::ssize(locked.y); ++t) ring.Update(locked.y[t], locked.z[t]);
  EXPECT_EQ(ring.history_size(), 150);
  for (const RestartEvent& e : ring.restart_events()) {
    EXPECT_EQ(e.replayed, std::min<long>(e.update, 150));
    EXPECT_EQ(e.dropped, e.update - e.replayed);
  }
}

// The leverage guard bounds a gross leverage point in a direction the data hardly inform (as an output
// glitch enters the lag differences of a slow ARX record): from a prior of ν0 = 4, V(0) = I, 100 samples of
// y = x₁ − 0.5x₂ + e with x₂ = x₁ + 0.01·v (x₁, v ~ N(0, 1), e ~ N(0, 0.1²)), then one sample with
// x₂ = x₁ + s (s = 10, 100, 1000) and a gross error (y = 0.5·x₁ where the model says 0.5·x₁ − 0.5·s).
// Unguarded, H0 has one maximum, the weight of new information, and the sample decides the weak
// direction: the coefficients move by 0.34. Guarded it is taken at β0, the information of one ordinary
// sample: they move by less than 0.01 whatever s.
TEST(StudentRegression, LeverageGuardBoundsAGrossLeveragePointWhateverItsSize) {
  for (const double s : {10.0, 100.0, 1000.0}) {
    double moved[2];
    for (const bool guard : {false, true}) {
      std::mt19937_64 rng(5);
      std::normal_distribution<double> g;
      StudentRegressionOptions o;
      o.prior = RegressionPrior::Diagonal(2, 4, 1, 1);
      o.leverage_guard = guard;
      StudentRegression est(2, o);
      est.set_outlying_regressor(false);  // the metric distance z'Ṽ_z⁻¹z decides
      for (int t = 0; t < 100; ++t) {
        const double x1 = g(rng);
        const Eigen::Vector2d z(x1, x1 + 0.01 * g(rng));
        est.Update(z.dot(Eigen::Vector2d(1, -0.5)) + 0.1 * g(rng), z);
      }
      const Eigen::Vector2d before = est.parameters();
      const double x1 = g(rng);
      est.Update(0.5 * x1, Eigen::Vector2d(x1, x1 + s));  // the model says 0.5·x₁ − 0.5·s
      moved[guard] = (est.parameters() - before).norm();
    }
    EXPECT_LT(moved[1], 0.01) << "s = " << s;
    EXPECT_GT(moved[0], 0.2) << "s = " << s;  // the unguarded reading follows the point
  }
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
  o.history_limit = 10;
  EXPECT_NE(message(o).find("history_limit = 10"), std::string::npos) << message(o);
  o = {};
  o.base.dof = -2;
  EXPECT_NE(message(o).find("dof = -2"), std::string::npos) << message(o);
}

}  // namespace
}  // namespace ident
