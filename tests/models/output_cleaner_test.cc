// Bounded regressor cleaning (models/output_cleaner.h) and the outlier decision (ident/regression/outlier_decision.h).
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "common/error.h"
#include "ident/regression/outlier_decision.h"
#include "models/arx.h"
#include "models/output_cleaner.h"

namespace ident::testing {
namespace {

using models::OutputCleaner;
using models::OutputCleaningOptions;

TEST(OutputCleaner, DisabledOrUnflaggedStoresTheMeasurement) {
  OutputCleaner off({.enabled = false, .warm_up = 1});
  OutputCleaner on({.enabled = true, .warm_up = 1});
  on.Clean(0.0, 0.0, 1.0, false);
  off.Clean(0.0, 0.0, 1.0, false);
  EXPECT_EQ(off.Clean(50.0, 0.0, 1.0, true), 50.0);
  EXPECT_EQ(on.Clean(0.7, 0.0, 1.0, false), 0.7);
  EXPECT_EQ(on.cleaned(), 0);
}

// With gross = 0 every flagged sample is cleaned with the Huber ψ: the prediction plus the clipped error.
TEST(OutputCleaner, FlaggedSampleBecomesThePredictionPlusTheClippedError) {
  OutputCleaner c({.enabled = true, .clip = 2.0, .max_run = 5, .warm_up = 2, .gross = 0});
  c.Clean(-10.0, 0.0, 1.0, true);  // warm-up: stored as is even when flagged
  c.Clean(10.0, 0.0, 1.0, true);
  EXPECT_EQ(c.cleaned(), 0);
  // y_c = ŷ + clip(y − ŷ, ±c·s) = 1 + clip(19, ±3) = 4 (eq. (1)); inside the range [−10, 10].
  EXPECT_DOUBLE_EQ(c.Clean(20.0, 1.0, 1.5, true), 4.0);
  EXPECT_DOUBLE_EQ(c.Clean(-20.0, 1.0, 1.5, true), -2.0);
  // A small flagged error is kept whole (|ê| ≤ c·s).
  EXPECT_DOUBLE_EQ(c.Clean(1.5, 1.0, 1.5, true), 1.5);
  EXPECT_EQ(c.cleaned(), 3);
}

TEST(OutputCleaner, StoredValuesNeverLeaveTheRangeOfTheMeasurements) {
  OutputCleaner c({.enabled = true, .clip = 3.0, .max_run = 100, .warm_up = 1});
  c.Clean(1.0, 0.0, 1.0, false);
  c.Clean(-1.0, 0.0, 1.0, false);
  EXPECT_DOUBLE_EQ(c.Clean(0.5, 1e6, 1.0, true), 1.0);  // a wild prediction is clamped (eq. (2))
  EXPECT_DOUBLE_EQ(c.Clean(0.5, -1e6, 1.0, true), -1.0);
}

TEST(OutputCleaner, AfterMaxRunCleanedSamplesTheMeasurementIsTrusted) {
  OutputCleaner c({.enabled = true, .clip = 1.0, .max_run = 2, .warm_up = 1});
  c.Clean(0.0, 0.0, 1.0, false);
  c.Clean(5.0, 0.0, 1.0, false);
  EXPECT_DOUBLE_EQ(c.Clean(5.0, 0.0, 1.0, true), 0.0);  // gross (too few errors known for a scale): ŷ
  EXPECT_DOUBLE_EQ(c.Clean(5.0, 0.0, 1.0, true), 0.0);
  EXPECT_DOUBLE_EQ(c.Clean(5.0, 0.0, 1.0, true), 5.0);  // run of 2 reached (eq. (3))
  EXPECT_DOUBLE_EQ(c.Clean(5.0, 0.0, 1.0, true), 0.0);  // the run restarts
}

TEST(OutputCleaner, NonFiniteInputsAndBadOptions) {
  OutputCleaner c({.enabled = true, .warm_up = 1});
  c.Clean(0.0, 0.0, 1.0, false);
  EXPECT_EQ(c.Clean(3.0, std::nan(""), 1.0, true), 3.0);
  EXPECT_EQ(c.cleaned(), 0);
  // The Huber clip (gross = 0) needs the estimator's scale: none, no cleaning. A gross error is judged by the
  // recent errors' scale alone, so an estimator scale of 0 does not keep it in.
  OutputCleaner clip({.enabled = true, .warm_up = 1, .gross = 0});
  clip.Clean(0.0, 0.0, 1.0, false);
  EXPECT_EQ(clip.Clean(3.0, 0.0, 0.0, true), 3.0);
  EXPECT_EQ(clip.cleaned(), 0);
  EXPECT_EQ(c.Clean(3.0, 0.0, 0.0, true), 0.0);
  EXPECT_EQ(c.cleaned(), 1);
  EXPECT_THROW(OutputCleaner({.clip = 0}), InvalidArgument);
  EXPECT_THROW(OutputCleaner({.max_run = 0}), InvalidArgument);
  EXPECT_THROW(OutputCleaner({.warm_up = -1}), InvalidArgument);
}

// The failure the issue reports for naive replacement: a wrong model fed its own predictions. Here
// the model is deliberately unstable (y(t) = 2.5 y(t−1) − 0.1 u(t−1), a pole at 2.5) and flags every
// sample. Naive replacement (store ŷ) is the model's simulation and explodes; the bounded cleaner keeps
// every stored output inside the measured range, and so every prediction bounded.
TEST(ArxRegressorCleaning, AWrongModelFlaggingEverythingCannotRunAway) {
  const models::ArxStructure arx(1, {1}, {1});
  models::ArxRegressor naive(arx);  // naive replacement: store ŷ for every flagged sample
  models::ArxRegressor bounded(arx, {.enabled = true, .clip = 2.0, .max_run = 2, .warm_up = 5, .gross = 0});
  const Eigen::Vector2d theta_wrong(-2.5, -0.1);  // z = [−y(t−1), u(t−1)]
  std::mt19937_64 rng(11);
  std::normal_distribution<double> noise(0.0, 0.1);
  double y_prev = 0, y_min = 0, y_max = 0, naive_max = 0, bounded_max_pred = 0;
  Eigen::VectorXd u(1), z(2);
  for (int t = 0; t < 400; ++t) {
    u(0) = std::sin(0.05 * t);
    const double y = 0.8 * y_prev + 0.5 * u(0) + noise(rng);  // the true (stable) system
    y_prev = y;
    y_min = std::min(y_min, y);
    y_max = std::max(y_max, y);
    if (naive.Next(u, z)) {
      const double y_hat = theta_wrong.dot(z);
      const double stored = t < 5 ? y : y_hat;
      naive.PushOutput(stored);
      naive_max = std::max(naive_max, std::abs(stored));
    } else {
      naive.PushOutput(y);
    }
    if (bounded.Next(u, z)) {
      const double y_hat = theta_wrong.dot(z);
      bounded_max_pred = std::max(bounded_max_pred, std::abs(y_hat));
      const double stored = bounded.PushCheckedOutput(y, y_hat, 0.1, true);
      EXPECT_GE(stored, y_min - 1e-12) << t;
      EXPECT_LE(stored, y_max + 1e-12) << t;
    } else {
      bounded.PushOutput(y);
    }
  }
  EXPECT_GT(naive_max, 1e100);  // naive replacement runs away
  // Bounded: |ŷ| ≤ 2.5·max|y| + 0.1·max|u| (the stored outputs lie in the measured range).
  EXPECT_LE(bounded_max_pred, 2.5 * std::max(-y_min, y_max) + 0.1 + 1e-12);
  EXPECT_GT(bounded.cleaner().cleaned(), 100);
}

// (4): during warm-up only a jump beyond `screen` robust scales of the stored differences is cleaned,
// towards the last stored value; `judged` = false (least squares) stores every measurement.
TEST(OutputCleaner, WarmUpScreensGrossJumpsModelFree) {
  OutputCleaner c({.enabled = true, .clip = 2.0, .warm_up = 100, .screen = 10});
  OutputCleaner ls({.enabled = true, .clip = 2.0, .warm_up = 100, .screen = 10});
  double y = 0;
  for (int t = 0; t < 20; ++t) {  // steps of ±1: s_Δ = 1.4826
    y += t % 2 ? 1.0 : -1.0;
    EXPECT_EQ(c.Clean(y, std::nan(""), std::nan(""), false), y);
    ls.Clean(y, 0, 1, false, /*judged=*/false);
  }
  EXPECT_EQ(c.Clean(y + 14.0, std::nan(""), std::nan(""), false), y + 14.0);  // 14 < 10·1.4826: kept
  const double last = y + 14.0;
  // 1000 ≫ 10·s_Δ: cleaned towards the last stored value, last + c·s_Δ, whatever the estimator says, and
  // clamped to the measured range, whose top is `last` (eq. (2)).
  EXPECT_DOUBLE_EQ(c.Clean(last + 1000, std::nan(""), std::nan(""), false), last);
  EXPECT_EQ(c.cleaned(), 1);
  EXPECT_EQ(ls.Clean(y + 1000, 0, 1, true, /*judged=*/false), y + 1000);
  EXPECT_EQ(ls.cleaned(), 0);
}

// (5): after warm-up a flagged sample is cleaned only if its error is gross against the recent errors.
TEST(OutputCleaner, AfterWarmUpOnlyGrossFlaggedErrorsAreCleaned) {
  OutputCleaner c({.enabled = true, .clip = 2.0, .max_run = 5, .warm_up = 1, .gross = 5});
  c.Clean(0.0, 0.0, 1.0, false);
  for (int t = 0; t < 16; ++t) c.Clean(t % 2 ? 0.1 : -0.1, 0.0, 1.0, false);  // errors ±0.1: scale 0.148
  EXPECT_EQ(c.Clean(0.5, 0.0, 0.05, true), 0.5);                              // flagged, but 0.5 < 5·0.148
  EXPECT_EQ(c.cleaned(), 0);
  EXPECT_DOUBLE_EQ(c.Clean(0.9, 0.05, 0.05, true), 0.05);  // gross: ψ = 0, the prediction ŷ, in range
  EXPECT_EQ(c.cleaned(), 1);
  EXPECT_THROW(OutputCleaner({.gross = -1}), InvalidArgument);
  EXPECT_THROW(OutputCleaner({.screen = std::nan("")}), InvalidArgument);
}

// EndWarmUp(): once the estimator has made its robust start, its predictions judge the samples (5) instead
// of the model-free screen (4), which lets through a jump the recent differences hide.
TEST(OutputCleaner, EndWarmUpHandsTheJudgementToTheModel) {
  for (const bool ended : {false, true}) {
    OutputCleaner c({.enabled = true, .max_run = 5, .warm_up = 100, .screen = 10, .gross = 5});
    for (int t = 0; t < 20; ++t) c.Clean(t % 2 ? 1.0 : -1.0, 0.0, 1.0, false);  // differences ±2: s_Δ ≈ 3
    if (ended) c.EndWarmUp();
    for (int t = 0; t < 16; ++t) c.Clean(t % 2 ? 0.9 : -0.9, t % 2 ? 1.0 : -1.0, 0.1, false);  // errors ±0.1
    // A jump of 8 from the last value: inside the screen's 10·s_Δ, but 80 robust scales of the errors.
    const double stored = c.Clean(-8.9, -1.0, 0.1, true);
    EXPECT_DOUBLE_EQ(stored, ended ? -1.0 : -8.9) << ended;
  }
}

// Additive outlier or innovation: the regressor with the measured y(t−1) is offered after a cleaning,
// and restoring it puts the measurement back into every later regressor.
TEST(ArxRegressorCleaning, MeasuredRegressorAndRestoreAfterACleanedOutput) {
  const models::ArxStructure arx(2, {1}, {1});  // z = [−y(t−1), −y(t−2), u(t−1)]
  models::ArxRegressor r(arx, {.enabled = true, .clip = 1.0, .max_run = 5, .warm_up = 2, .gross = 0});
  Eigen::VectorXd u(1), z(3), zm(3);
  u(0) = 0.5;
  for (double y : {1.0, 2.0, 3.0}) {
    r.Next(u, z);
    r.PushCheckedOutput(y, 0.0, 1.0, false);
  }
  EXPECT_TRUE(r.Next(u, z));
  EXPECT_FALSE(r.MeasuredRegressor(zm));                             // nothing cleaned
  EXPECT_DOUBLE_EQ(r.PushCheckedOutput(50.0, 2.5, 0.5, true), 3.0);  // 2.5 + clip(47.5, ±0.5), range [1, 3]
  EXPECT_TRUE(r.Next(u, z));
  EXPECT_EQ(z, Eigen::Vector3d(-3.0, -3.0, 0.5));
  ASSERT_TRUE(r.MeasuredRegressor(zm));
  EXPECT_EQ(zm, Eigen::Vector3d(-50.0, -3.0, 0.5));
  r.RestoreMeasured();
  EXPECT_EQ(r.cleaner().cleaned(), 0);
  EXPECT_FALSE(r.MeasuredRegressor(zm));  // decided
  r.PushCheckedOutput(4.0, 4.0, 1.0, false);
  EXPECT_TRUE(r.Next(u, z));
  EXPECT_EQ(z, Eigen::Vector3d(-4.0, -50.0, 0.5));  // the measurement, not the cleaned 3
}

// During the warm-up no model judges: an output the model-free screen cleaned is told an additive outlier
// (the next output returns to the cleaned level) or a step (it stays at the measured one) by the
// screen's own predictor, the last stored value; after the warm-up the model's predictions decide.
TEST(ArxRegressorCleaning, TheWarmUpScreenTellsAnAdditiveOutlierFromAStep) {
  const models::ArxStructure arx(1, {1}, {1});  // z = [−y(t−1), u(t−1)]
  Eigen::VectorXd u(1), z(2), zm(2);
  u(0) = 0.0;
  for (const double next : {1.1, 49.0}) {  // back near 1 (additive), or staying near 50 (a step)
    models::ArxRegressor r(arx, {.enabled = true, .warm_up = 20});
    for (double y : {1.0, 1.2, 0.9, 1.1, 1.0, 0.8, 1.0}) {  // differences with robust scale ~0.3
      r.Next(u, z);
      r.PushCheckedOutput(y, std::nan(""), 1.0, false);
    }
    r.Next(u, z);
    EXPECT_DOUBLE_EQ(r.PushCheckedOutput(50.0, std::nan(""), 1.0, false), 1.0);  // screened: the last value
    r.Next(u, z);
    ASSERT_TRUE(r.MeasuredRegressor(zm));
    ASSERT_TRUE(r.MeasuredIsNearer(next).has_value());
    EXPECT_EQ(*r.MeasuredIsNearer(next), next > 25) << next;
  }
  // After the warm-up a cleaning is the model's: no model-free verdict.
  models::ArxRegressor r(arx, {.enabled = true, .warm_up = 2, .gross = 0});
  for (double y : {1.0, 1.2, 0.9}) {
    r.Next(u, z);
    r.PushCheckedOutput(y, 1.0, 0.1, false);
  }
  r.Next(u, z);
  r.PushCheckedOutput(50.0, 1.0, 0.1, true);
  r.Next(u, z);
  ASSERT_TRUE(r.MeasuredRegressor(zm));
  EXPECT_FALSE(r.MeasuredIsNearer(1.0).has_value());
}

TEST(OutlierDecision, FlagsSmallRelativeWeightsOnlyOnUpdatedSteps) {
  const OutlierDecision d;                                          // 0.2
  EXPECT_FALSE(d.Flags({StepStatus::kUpdated, 0.01, 100.0, 0.0}));  // νβ = 1 (RLS)
  EXPECT_TRUE(d.Flags({StepStatus::kUpdated, 0.001, 100.0, 0.0}));  // νβ = 0.1
  EXPECT_FALSE(d.Flags({StepStatus::kRejectedInvalid, 0.001, 100.0, 0.0}));
  EXPECT_FALSE(d.Flags({StepStatus::kUpdated}));  // NaN weight
  EXPECT_NE(OutlierDecision{1.5}.Validate(), "");
  EXPECT_EQ(OutlierDecision{0.3}.Validate(), "");
}

}  // namespace
}  // namespace ident::testing
