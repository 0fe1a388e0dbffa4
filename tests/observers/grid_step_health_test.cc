// Grid observer steps are the whole step or nothing (found by grid_observer_fuzzer): invalid models
// are rejected, and a step whose result is not a finite, normalised density with finite moments is
// reported as kNumericalFailure with the density, the grid and the moments bit-for-bit unchanged.
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Core>

#include "common/step_report.h"
#include "ident/observers/grid_observer.h"
#include "models/measurement.h"
#include "models/state_space.h"

namespace ident {
namespace {

struct GridState {
  std::vector<double> density, origin, spacing;
  Eigen::VectorXd mean;
  Eigen::MatrixXd covariance;
};

GridState StateOf(const GridObserver& g) {
  GridState s{g.density(), {}, {}, g.mean(), g.covariance()};
  for (int i = 0; i < g.dim(); ++i) {
    s.origin.push_back(g.origin(i));
    s.spacing.push_back(g.spacing(i));
  }
  return s;
}

void ExpectSameState(const GridState& a, const GridState& b, const std::string& what) {
  EXPECT_TRUE(a.density == b.density) << what << ": density";
  EXPECT_TRUE(a.origin == b.origin && a.spacing == b.spacing) << what << ": grid";
  EXPECT_TRUE(a.mean == b.mean && a.covariance == b.covariance) << what << ": moments";
}

// Σ p · cell, computed independently of the observer's Normalise().
double Mass(const GridObserver& g) {
  double cell = 1, sum = 0;
  for (int i = 0; i < g.dim(); ++i) cell *= g.spacing(i);
  for (double p : g.density()) sum += p * cell;
  return sum;
}

GridObserver MakeGrid(int n, int points = 12) {
  GridObserverOptions options;
  options.points.assign(n, points);
  return GridObserver(Eigen::VectorXd::Zero(n), Eigen::MatrixXd::Identity(n, n), options);
}

models::LinearStateSpace Model(int n, double a, double b, double q) {
  return models::LinearStateSpace{a * Eigen::MatrixXd::Identity(n, n), Eigen::MatrixXd::Constant(n, 1, b),
                                  q * Eigen::MatrixXd::Identity(n, n)};
}

TEST(GridObserverStepHealth, PredictRejectsNonFiniteOrMisshapenModelsAndKeepsTheState) {
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  GridObserver grid = MakeGrid(2);
  const GridState before = StateOf(grid);
  const Eigen::VectorXd u = Eigen::VectorXd::Ones(1);
  auto expect_rejected = [&](const models::LinearStateSpace& m, const Eigen::VectorXd& input, const std::string& what) {
    EXPECT_EQ(grid.Predict(m, input).status, StepStatus::kRejectedInvalid) << what;
    ExpectSameState(StateOf(grid), before, what);
  };
  models::LinearStateSpace m = Model(2, 0.9, 0.1, 0.01);
  m.A(0, 1) = nan;
  expect_rejected(m, u, "NaN in A");
  m = Model(2, 0.9, 0.1, 0.01);
  m.B(1, 0) = inf;
  expect_rejected(m, u, "Inf in B");
  m = Model(2, 0.9, 0.1, 0.01);
  m.process_noise(0, 0) = nan;
  expect_rejected(m, u, "NaN in the process noise");
  expect_rejected(Model(2, 0.9, 0.1, 0.01), Eigen::VectorXd::Constant(1, inf), "Inf input");
  m = Model(2, 0.9, 0.1, 0.01);
  m.B = Eigen::MatrixXd::Ones(3, 1);
  expect_rejected(m, u, "B with 3 rows");
  m = Model(2, 0.9, 0.1, 0.01);
  m.process_noise = Eigen::MatrixXd::Identity(3, 3);
  expect_rejected(m, u, "3x3 process noise");
  expect_rejected(Model(2, 0.0, 0.1, 0.01), u, "singular A");
  expect_rejected(Model(2, 1e-320, 0.1, 0.01), u, "A whose inverse overflows");
  // A healthy step afterwards is taken and normalised.
  ASSERT_TRUE(grid.Predict(Model(2, 0.9, 0.1, 0.01), u).updated());
  EXPECT_NEAR(Mass(grid), 1.0, 1e-12);
}

TEST(GridObserverStepHealth, PredictBeyondDoubleRangeFailsAndKeepsTheState) {
  // 1-D, A = 1e300: the box is finite (±8e300) but the variance of the image, ~1e601, overflows.
  // Before the fix the step was reported as updated with an infinite covariance.
  GridObserver one = MakeGrid(1);
  GridState before = StateOf(one);
  EXPECT_EQ(one.Predict(Model(1, 1e300, 0.0, 0.0), Eigen::VectorXd::Zero(1)).status, StepStatus::kNumericalFailure);
  ExpectSameState(StateOf(one), before, "1-D, A = 1e300");
  // 2-D, A = 1e200: the cell volume (~1e400) overflows. Before the fix Normalise scaled the density by
  // 1/∞ and the step was reported as updated with a density of zeros.
  GridObserver two = MakeGrid(2);
  before = StateOf(two);
  EXPECT_EQ(two.Predict(Model(2, 1e200, 0.0, 0.0), Eigen::VectorXd::Zero(1)).status, StepStatus::kNumericalFailure);
  ExpectSameState(StateOf(two), before, "2-D, A = 1e200");
  // B u = 1e308 · 1e308 = ∞: the box's centre overflows. Before the fix the interpolation cast the NaN
  // fractional node index to int and read out of bounds (a segmentation fault).
  before = StateOf(two);
  EXPECT_EQ(two.Predict(Model(2, 1.0, 1e308, 0.0), Eigen::VectorXd::Constant(1, 1e308)).status,
            StepStatus::kNumericalFailure);
  ExpectSameState(StateOf(two), before, "B u = inf");
  // The observer carries on: a healthy step is taken; its mean is A m + B u exactly up to grid error.
  ASSERT_TRUE(two.Predict(Model(2, 0.5, 1.0, 0.01), Eigen::VectorXd::Constant(1, 2.0)).updated());
  EXPECT_NEAR(Mass(two), 1.0, 1e-12);
  EXPECT_NEAR(two.mean()(0), 2.0, 2 * two.spacing(0));
  EXPECT_NEAR(two.mean()(1), 2.0, 2 * two.spacing(1));
}

// A user-defined measurement whose log-likelihood is NaN for x > 0 (a broken model).
class NanForPositiveStates final : public models::MeasurementFunction {
 public:
  std::string name() const override { return "nan-for-positive"; }
  int num_states() const override { return 1; }
  double LogLikelihood(double, const Eigen::Ref<const Eigen::VectorXd>& x) const override {
    return x(0) > 0 ? std::numeric_limits<double>::quiet_NaN() : -x(0) * x(0);
  }
  Eigen::MatrixXd Strength(double) const override { return Eigen::MatrixXd::Zero(1, 1); }
  bool IsValidOutput(double y) const override { return std::isfinite(y); }
};

TEST(GridObserverStepHealth, CorrectWithANanLikelihoodFailsAndKeepsTheDensity) {
  // Before the fix the density was multiplied by exp(NaN) before the failure was noticed.
  GridObserver grid = MakeGrid(1, 32);  // spacing 16/31: lattice sums of these Gaussians are exact to ~e^-37
  const GridState before = StateOf(grid);
  EXPECT_EQ(grid.Correct(NanForPositiveStates(), 0.0).status, StepStatus::kNumericalFailure);
  ExpectSameState(StateOf(grid), before, "NaN likelihood");
  // A proper reading is then taken: N(0, 1) prior, y = x + e, e ~ N(0, 1), y = 1: mean 1/2, variance 1/2.
  models::GaussianMeasurement reading(Eigen::VectorXd::Ones(1), 1.0);
  ASSERT_TRUE(grid.Correct(reading, 1.0).updated());
  EXPECT_NEAR(Mass(grid), 1.0, 1e-12);
  EXPECT_NEAR(grid.mean()(0), 0.5, 1e-9);
  EXPECT_NEAR(grid.covariance()(0, 0), 0.5, 1e-9);
}

TEST(GridObserverStepHealth, AReadingLeavingOneSubnormalNodeGivesThatNodesMoments) {
  // Prior N(0, 1) on 8 nodes over ±s sd, s ∈ [38, 38.5]: the end node's density, about 1e5 · e^(−s²/2), is
  // subnormal (1e−307 down to a few hundred units of 2^−1074). A threshold reading x ≥ 34 keeps that node
  // alone (its cell starts at 6s/7 ≤ 33), so the posterior is all at x = s: mean s, variance 0, whatever
  // the precision of the node's value. Taken on the subnormal values themselves, the moments round each
  // product to a multiple of 2^−1074 (a variance of 2e−13 at s = 38; found by grid_observer_fuzzer as a
  // mean outside the grid), and the normalisation 1 / (Σ p · cell) overflows (the reading is refused).
  for (double s = 38.0; s <= 38.5; s += 0.025) {
    GridObserverOptions options;
    options.points = {8};
    options.initial_sigmas = s;
    GridObserver grid(Eigen::VectorXd::Zero(1), Eigen::MatrixXd::Identity(1, 1), options);
    const double end = grid.axis(0, 7);
    ASSERT_GT(grid.density()[7], 0.0) << "s = " << s;
    ASSERT_LT(grid.density()[7], std::numeric_limits<double>::min()) << "s = " << s;
    models::ThresholdSensor above(Eigen::VectorXd::Ones(1), 34.0);
    ASSERT_TRUE(grid.Correct(above, 1.0).updated()) << "s = " << s;
    EXPECT_NEAR(Mass(grid), 1.0, 1e-12) << "s = " << s;
    EXPECT_NEAR(grid.mean()(0), end, 1e-13 * end) << "s = " << s;
    EXPECT_LE(grid.covariance()(0, 0), 1e-24) << "s = " << s;
    for (int j = 0; j < 7; ++j) EXPECT_EQ(grid.density()[j], 0.0) << "s = " << s << ", node " << j;
  }
}

}  // namespace
}  // namespace ident
