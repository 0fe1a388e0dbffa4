// The lagged-output screen of the robust starts (ident/regression/internal/lagged_output_screen.h) against the
// ground truth of simulated records: which outputs were moved (additive outliers), which rows carry them.
#include "ident/regression/internal/lagged_output_screen.h"

#include <random>
#include <set>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Core>

#include "ident/regression/safe_student_regression.h"
#include "tests/regression/lock_in_data.h"

namespace ident {
namespace {

using internal::LaggedOutputScreen;
using internal::ScreenLaggedOutputs;

// ARX(2,2) y(t) = 1.5 y(t−1) − 0.7 y(t−2) + u(t−1) + 0.5 u(t−2) + e(t), e ~ N(0, 0.1²), binary u that switches
// with probability 0.2, n rows (y(t), −y(t−1), −y(t−2), u(t−1), u(t−2)) of the measured outputs, in which the
// outputs at `moved` (row indices) are moved by ±size after the simulation.
Eigen::MatrixXd AdditiveOutlierWindow(unsigned seed, int n, const std::set<int>& moved, double size) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> e(0, 0.1);
  std::uniform_real_distribution<double> uni(0, 1);
  const int m = n + 2;  // two outputs before the first row
  std::vector<double> y(m, 0), u(m, 1);
  for (int t = 1; t < m; ++t) u[t] = uni(rng) < 0.2 ? -u[t - 1] : u[t - 1];
  for (int t = 2; t < m; ++t) y[t] = 1.5 * y[t - 1] - 0.7 * y[t - 2] + u[t - 1] + 0.5 * u[t - 2] + e(rng);
  for (int r : moved) y[r + 2] += uni(rng) < 0.5 ? -size : size;
  Eigen::MatrixXd w(n, 5);
  for (int r = 0; r < n; ++r) {
    const int t = r + 2;
    w.row(r) << y[t], -y[t - 1], -y[t - 2], u[t - 1], u[t - 2];
  }
  return w;
}

std::set<int> Rows(const Eigen::Array<bool, Eigen::Dynamic, 1>& mask) {
  std::set<int> rows;
  for (int i = 0; i < mask.size(); ++i)
    if (mask(i)) rows.insert(i);
  return rows;
}

// The rows whose two lagged outputs include a moved one.
std::set<int> Carriers(const std::set<int>& moved, int n) {
  std::set<int> rows;
  for (int r : moved)
    for (int lag : {1, 2})
      if (r + lag < n) rows.insert(r + lag);
  return rows;
}

// Gross additive outliers (100σ and 1000σ) at 10 % of the rows, some in runs: the screen flags exactly the moved
// outputs and leaves out exactly the rows that carry them, at the start of a record (the first 40 rows, where
// the robust start is made) and over a whole record.
TEST(LaggedOutputScreen, FlagsExactlyTheMovedOutputsAndTheRowsThatCarryThem) {
  const std::set<int> early = {1, 2, 9, 23, 31};
  for (double size : {10.0, 100.0}) {
    for (unsigned seed = 1; seed <= 20; ++seed) {
      const LaggedOutputScreen s = ScreenLaggedOutputs(AdditiveOutlierWindow(seed, 40, early, size));
      ASSERT_TRUE(s.linked);
      EXPECT_EQ(Rows(s.flagged), early) << "seed " << seed << ", size " << size;
      EXPECT_EQ(Rows(s.poisoned), Carriers(early, 40)) << "seed " << seed << ", size " << size;
    }
  }
  std::mt19937_64 rng(7);
  std::set<int> moved;
  while (moved.size() < 60) moved.insert(static_cast<int>(rng() % 600));
  const LaggedOutputScreen s = ScreenLaggedOutputs(AdditiveOutlierWindow(3, 600, moved, 10.0));
  EXPECT_EQ(Rows(s.flagged), moved);
  EXPECT_EQ(Rows(s.poisoned), Carriers(moved, 600));
}

// An output from before the first row (row −1 or −2 here), which only the regressors of the first rows carry,
// has no row of its own in which to be judged: when it is gross, the rows that carry it are left out (their
// error is gross), and their own outputs, which are clean, are not flagged. The outliers within the window are
// found as before.
TEST(LaggedOutputScreen, LeavesOutTheRowsThatCarryAGrossOutputFromBeforeTheWindow) {
  const std::set<int> within = {9, 23, 31};
  for (double size : {10.0, 100.0}) {
    for (unsigned seed = 1; seed <= 20; ++seed) {
      std::set<int> moved = within;
      moved.insert(-1);  // y(−1): carried by rows 0 (lag 1) and 1 (lag 2)
      LaggedOutputScreen s = ScreenLaggedOutputs(AdditiveOutlierWindow(seed, 40, moved, size));
      ASSERT_TRUE(s.linked);
      EXPECT_EQ(Rows(s.flagged), within) << "seed " << seed << ", size " << size;
      std::set<int> carriers = Carriers(within, 40);
      carriers.insert({0, 1});
      EXPECT_EQ(Rows(s.poisoned), carriers) << "seed " << seed << ", size " << size;

      moved = within;
      moved.insert(-2);  // y(−2): carried by row 0 alone (lag 2)
      s = ScreenLaggedOutputs(AdditiveOutlierWindow(seed, 40, moved, size));
      EXPECT_EQ(Rows(s.flagged), within) << "seed " << seed << ", size " << size;
      carriers = Carriers(within, 40);
      carriers.insert(0);
      EXPECT_EQ(Rows(s.poisoned), carriers) << "seed " << seed << ", size " << size;
    }
  }
}

// Innovation outliers (±5 = 50σ in e(t), carried on by the dynamics) are no reason to leave rows out: the row
// after one is predicted better from the measured output than from its prediction. Only where a second
// innovation follows the first at once (its own error gross either way) does the pair read as additive: over
// ten records of 300 rows with 10 % innovations, at most 1 % of the rows after the first two are left out. In
// the first two rows, which carry outputs from before the window, an innovation reads as a gross output
// carried from there (ScreenLaggedOutputs cannot tell them apart) and its row is left out: there, at most the
// rows with an innovation.
TEST(LaggedOutputScreen, LeavesInnovationOutliersIn) {
  long poisoned = 0, poisoned_first = 0, innovations_first = 0;
  for (unsigned seed = 1; seed <= 10; ++seed) {
    const testing::LockInArx d = testing::SimulateLockInArx(seed, 302);
    Eigen::MatrixXd w(300, 5);
    for (int i = 0; i < 300; ++i) w.row(i) << d.y[i], d.z[i].transpose();
    const LaggedOutputScreen s = ScreenLaggedOutputs(w);
    EXPECT_TRUE(s.linked);
    poisoned += s.poisoned.tail(298).count();
    poisoned_first += s.poisoned.head(2).count();
    for (int i = 0; i < 2; ++i) innovations_first += std::abs(d.y[i] - testing::kLockInTheta.dot(d.z[i])) > 1.0;
  }
  EXPECT_LE(poisoned, 30);
  EXPECT_LE(poisoned_first, innovations_first);
}

// Without a regressor that carries earlier outputs nothing is linked or left out: a static regression, a
// window whose outputs are constant, and an ARX window whose lagged outputs are stored rounded (not copies).
TEST(LaggedOutputScreen, NeedsExactCopiesOfVaryingOutputs) {
  Eigen::MatrixXd w = AdditiveOutlierWindow(5, 60, {10, 30}, 100.0);
  Eigen::MatrixXd rounded = w;
  rounded.rightCols(4) = (w.rightCols(4).array() * 1e6).round() / 1e6;
  EXPECT_FALSE(ScreenLaggedOutputs(rounded).linked);
  Eigen::MatrixXd constant = w;
  constant.col(0).setConstant(2.0);
  constant.col(1).setConstant(-2.0);
  constant.col(2).setConstant(-2.0);
  EXPECT_FALSE(ScreenLaggedOutputs(constant).linked);
  std::mt19937_64 rng(11);
  std::normal_distribution<double> g(0, 1);
  Eigen::MatrixXd stat(50, 4);
  for (int i = 0; i < 50; ++i) {
    stat.row(i) << 0, g(rng), g(rng), g(rng);
    stat(i, 0) = stat.row(i).tail(3).sum() + 0.1 * g(rng) + (i % 10 == 0 ? 50 : 0);
  }
  const LaggedOutputScreen s = ScreenLaggedOutputs(stat);
  EXPECT_FALSE(s.linked);
  EXPECT_FALSE(s.flagged.any());
  EXPECT_FALSE(s.poisoned.any());
}

// A row left out between two samples (a missing value, an equation the workflow skipped) breaks the links
// across it: the row after the gap carries no output of the row before it, so an outlier before the gap
// poisons nothing after it.
TEST(LaggedOutputScreen, LinksHoldOnlyWhereTheCopiesAre) {
  const std::set<int> moved = {20};
  const Eigen::MatrixXd full = AdditiveOutlierWindow(9, 80, moved, 100.0);
  Eigen::MatrixXd gapped(79, 5);
  gapped << full.topRows(21), full.bottomRows(58);  // row 21 (which carries y of row 20 at lag 1) left out
  const LaggedOutputScreen s = ScreenLaggedOutputs(gapped);
  ASSERT_TRUE(s.linked);
  EXPECT_EQ(Rows(s.flagged), moved);
  EXPECT_EQ(Rows(s.poisoned), std::set<int>{21});  // the old row 22, which carries y of row 20 at lag 2
}

// The estimator alone (no output cleaning by a workflow) on ARX records with 10 % additive outliers of 100σ:
// every poisoned row reaches it. Student-t (k = 3) maximum likelihood over such rows is a wrong Θ; at the end
// of the data the restart from the robust fit of the rows that carry no gross output outlier, replayed on those
// rows alone, wins — and says how many it left out.
TEST(LaggedOutputScreen, EndOfDataRestartLeavesOutTheRowsThatCarryGrossOutliers) {
  const Eigen::Vector4d truth(-1.5, 0.7, 1.0, 0.5);  // in the rows' convention (−y(t−1), −y(t−2), u(t−1), u(t−2))
  for (unsigned seed = 1; seed <= 10; ++seed) {
    std::mt19937_64 rng(seed);
    std::set<int> moved;
    while (moved.size() < 50) moved.insert(static_cast<int>(rng() % 500));
    const Eigen::MatrixXd w = AdditiveOutlierWindow(seed, 500, moved, 10.0);
    SafeStudentOptions o;
    o.base.dof = 3;
    SafeStudentRegression est(4, o);
    for (Eigen::Index i = 0; i < w.rows(); ++i) est.Update(w(i, 0), w.row(i).tail(4).transpose());
    est.ReconsiderAtEnd();
    EXPECT_LT((est.parameters() - truth).norm(), 0.05 * truth.norm()) << "seed " << seed;
    ASSERT_FALSE(est.restart_events().empty()) << "seed " << seed;
    const RestartEvent& e = est.restart_events().back();
    EXPECT_TRUE(e.end_of_data) << "seed " << seed;
    EXPECT_GE(e.left_out, 50) << "seed " << seed;  // most of the ~100 rows that carry one of the 50
    EXPECT_EQ(e.replayed + e.left_out + e.dropped, 500) << "seed " << seed;
  }
}

}  // namespace
}  // namespace ident
