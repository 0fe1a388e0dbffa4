// Run-time selection of observers by name: each name builds the observer it documents (same numbers as
// the concrete class on the same data, and on a linear-Gaussian model all three agree with the Kalman
// filter to the grid's discretisation error), options reach the observer, and every bad spec, option or
// problem is refused with a message naming the observer and the option.
#include <cmath>
#include <cstring>
#include <memory>
#include <random>
#include <string>

#include <gtest/gtest.h>
#include <Eigen/Cholesky>

#include "common/error.h"
#include "ident/observers/grid_observer.h"
#include "ident/observers/kalman_filter.h"
#include "ident/observers/lc_gaussian_filter.h"
#include "ident/observers/truncated_gaussian_filter.h"
#include "ident/registry/observer_registry.h"
#include "tests/observers/linear_gaussian_data.h"
#include "tests/registry/spec_error.h"

namespace ident {
namespace {

// Expects `what` to contain `part` (printed in full on failure).
#define EXPECT_CONTAINS(what, part) EXPECT_NE(std::string(what).find(part), std::string::npos) << (what)

using testing::Model2d;

ObserverProblem GaussianProblem() {
  return {Model2d(), std::make_shared<models::GaussianMeasurement>(Eigen::Vector2d(1.0, 0.5), 0.2),
          Eigen::Vector2d(0.0, 0.0), Eigen::Matrix2d::Identity()};
}

using testing::SpecError;

TEST(ObserverRegistry, ListsTheFourObservers) {
  EXPECT_EQ(StateObserverNames(), (std::vector<std::string>{"kalman", "lc_gaussian", "lc_truncated", "grid"}));
}

TEST(ObserverRegistry, EachNameBuildsTheDocumentedObserver) {
  const auto problem = GaussianProblem();
  const auto items = testing::SimulateLinearGaussian(problem.model, Eigen::Vector2d(1.0, 0.5), 0.2, 60, 4);
  auto kalman = MakeStateObserver(ParseEstimatorSpec("kalman"), problem);
  auto lc = MakeStateObserver(ParseEstimatorSpec("lc_gaussian"), problem);
  auto grid = MakeStateObserver(ParseEstimatorSpec("grid:points=96"), problem);
  EXPECT_EQ(kalman->name(), "kalman");
  EXPECT_EQ(lc->name(), "lc_gaussian");
  EXPECT_EQ(grid->name(), "grid");
  const auto& gaussian = static_cast<const models::GaussianMeasurement&>(*problem.measurement);
  KalmanFilter direct(problem.model, gaussian, problem.x0, problem.P0);
  GridObserverOptions gopt;
  gopt.points = {96, 96};
  GridObserver grid_direct(problem.model, problem.measurement, problem.x0, problem.P0, gopt);
  // Reference covariance form, written out here.
  Eigen::Vector2d x = problem.x0;
  Eigen::Matrix2d P = problem.P0;
  const Eigen::Vector2d c(1.0, 0.5);
  for (const auto& d : items) {
    ASSERT_TRUE(kalman->Update(d).updated());
    ASSERT_TRUE(lc->Update(d).updated());
    ASSERT_TRUE(grid->Update(d).updated());
    direct.Update(d);
    grid_direct.Update(d);
    x = problem.model.A * x + problem.model.B * d.u;
    P = problem.model.A * P * problem.model.A.transpose() + problem.model.process_noise;
    const double s = c.dot(P * c) + 0.2;
    const Eigen::Vector2d k = P * c / s;
    x += k * (d.y - c.dot(x));
    P -= k * k.transpose() * s;
  }
  EXPECT_EQ(kalman->num_states(), 2);
  EXPECT_LT((kalman->mean() - direct.mean()).norm(), 1e-15);
  EXPECT_LT((kalman->mean() - x).norm(), 1e-10);
  EXPECT_LT((lc->mean() - x).norm(), 1e-10);
  EXPECT_LT((lc->covariance() - P).norm(), 1e-12);
  EXPECT_LT((grid->mean() - grid_direct.mean()).norm(), 1e-15);  // options reached the grid observer
  // Grid against the Kalman filter to its discretisation error (as in observers_agree_test).
  const auto& g = static_cast<StateObserverModel<GridObserver>&>(*grid).get();
  const double d2 = std::max(g.spacing(0) * g.spacing(0), g.spacing(1) * g.spacing(1));
  EXPECT_LT((grid->mean() - x).cwiseAbs().maxCoeff(), 0.5 * std::sqrt(d2));
  EXPECT_LT((grid->covariance() - P).cwiseAbs().maxCoeff(), 3 * d2);
  EXPECT_EQ(g.points(0), 96);
}

TEST(ObserverRegistry, GridTakesPointsPerAxisAndItsOtherOptions) {
  auto grid = MakeStateObserver(ParseEstimatorSpec("grid:points=40x24,noise_sigmas=5,initial_sigmas=7,padding=10"),
                                GaussianProblem());
  const auto& g = static_cast<StateObserverModel<GridObserver>&>(*grid).get();
  EXPECT_EQ(g.points(0), 40);
  EXPECT_EQ(g.points(1), 24);
  EXPECT_NEAR(g.axis(0, 39) - g.axis(0, 0), 2 * 7.0, 1e-12);  // prior sd 1, ±initial_sigmas
}

TEST(ObserverRegistry, BadSpecsOptionsAndProblemsNameTheObserverAndOption) {
  const auto problem = GaussianProblem();
  EXPECT_CONTAINS(SpecError("kalmann", problem),
                  "unknown observer 'kalmann' (known: kalman, lc_gaussian, lc_truncated, grid)");
  EXPECT_CONTAINS(SpecError("kalman:points=3", problem), "observer 'kalman' takes no options; got 'points'");
  EXPECT_CONTAINS(SpecError("lc_gaussian:x=1", problem), "observer 'lc_gaussian' takes no options; got 'x'");
  EXPECT_CONTAINS(SpecError("grid:point=64", problem), "observer 'grid' has no option 'point'");
  EXPECT_CONTAINS(SpecError("grid:points=abc", problem), "option points = 'abc' is not a finite number");
  EXPECT_CONTAINS(SpecError("grid:points=6.5", problem), "option points = '6.5' is not an integer");
  EXPECT_CONTAINS(SpecError("grid:points=4", problem), "observer 'grid': option points = 4; need 8 <= points");
  EXPECT_CONTAINS(SpecError("grid:points=8x8x8", problem), "has 3 counts; need 1 or 2");
  EXPECT_CONTAINS(SpecError("grid:noise_sigmas=-1", problem), "option noise_sigmas = -1; need >= 0");
  EXPECT_CONTAINS(SpecError("grid:support_level=nan", problem), "support_level = 'nan' is not a finite number");
  EXPECT_CONTAINS(SpecError("grid:points", problem), "'points' is not a number or key=value");
  EXPECT_CONTAINS(SpecError("grid:points=8,points=9", problem), "option points given twice");
  EXPECT_CONTAINS(SpecError(":points=8", problem), "has no name");
  auto threshold = problem;
  threshold.measurement = std::make_shared<models::ThresholdSensor>(Eigen::Vector2d(1, 0), 1.0);
  EXPECT_CONTAINS(SpecError("kalman", threshold), "'kalman' needs a linear-Gaussian measurement; 'threshold'");
  EXPECT_NO_THROW(MakeStateObserver(ParseEstimatorSpec("lc_gaussian"), threshold));
  auto bad_prior = problem;
  bad_prior.P0 = Eigen::Matrix2d::Zero();
  EXPECT_CONTAINS(SpecError("kalman", bad_prior), "P0 is not positive definite");
  auto four = problem;
  four.x0 = Eigen::Vector4d::Zero();
  EXPECT_CONTAINS(SpecError("grid", four), "observer 'grid' handles 1 to 3 states; the problem has 4");
  auto null_meas = problem;
  null_meas.measurement = nullptr;
  EXPECT_CONTAINS(SpecError("lc_gaussian", null_meas), "measurement must not be null");
}

// lc_truncated on the MEMS accelerometer with its threshold sensor: the registry's observer is the filter
// driven directly through Step(), bit for bit.
TEST(ObserverRegistry, LcTruncatedEqualsTheDirectlyDrivenFilterBitForBit) {
  const auto model = models::MemsAccelerometerDynamics(0.01, 1.0);
  const auto sensor = std::make_shared<models::ThresholdSensor>(Eigen::Vector2d(1, 0), 1.0);
  const Eigen::Vector2d x0(0, 2);
  Eigen::Matrix2d P0;
  P0 << 0.3, 0, 0, 1;
  const auto items = testing::SimulateThresholdSensor(model, *sensor, 400, 11);
  auto obs = MakeStateObserver(ParseEstimatorSpec("lc_truncated"), {model, sensor, x0, P0});
  EXPECT_EQ(obs->name(), "lc_truncated");
  EXPECT_EQ(obs->num_states(), 2);
  TruncatedGaussianFilter direct(*sensor, x0, P0);
  int events = 0;
  for (const auto& d : items) {
    ASSERT_TRUE(obs->Update(d).updated());
    ASSERT_TRUE(direct.Step(model, d.u, d.y).updated());
    events += d.y != 0;
  }
  EXPECT_GT(events, 5);  // the record crosses the thresholds
  const Eigen::VectorXd m = obs->mean(), md = direct.mean();
  const Eigen::MatrixXd P = obs->covariance(), Pd = direct.covariance();
  EXPECT_EQ(std::memcmp(m.data(), md.data(), 2 * sizeof(double)), 0) << m.transpose() << " vs " << md.transpose();
  EXPECT_EQ(std::memcmp(P.data(), Pd.data(), 4 * sizeof(double)), 0) << P << "\nvs\n" << Pd;
  EXPECT_EQ(direct.failures(), 0);
}

TEST(ObserverRegistry, LcTruncatedNeedsATwoStateThresholdSensorAndTakesNoOptions) {
  auto mems = GaussianProblem();
  mems.model = models::MemsAccelerometerDynamics(0.01, 1.0);
  EXPECT_EQ(SpecError("lc_truncated", mems),
            "observer 'lc_truncated' needs a threshold sensor on 2 states; "
            "'gaussian' is not (use lc_gaussian or grid)");
  mems.measurement = std::make_shared<models::ThresholdSensor>(Eigen::Vector2d(1, 0), 1.0);
  EXPECT_EQ(SpecError("lc_truncated:points=3", mems), "observer 'lc_truncated' takes no options; got 'points'");
  EXPECT_NO_THROW(MakeStateObserver(ParseEstimatorSpec("lc_truncated"), mems));
  auto three = mems;
  three.measurement = std::make_shared<models::ThresholdSensor>(Eigen::Vector3d(1, 0, 0), 1.0);
  EXPECT_EQ(SpecError("lc_truncated", three),
            "observer 'lc_truncated' needs a threshold sensor on 2 states; "
            "'threshold' is not (use lc_gaussian or grid)");
  auto bad_prior = mems;
  bad_prior.P0 = Eigen::Matrix2d::Zero();
  EXPECT_CONTAINS(SpecError("lc_truncated", bad_prior), "prior covariance not positive definite");
  auto wrong_size = mems;
  wrong_size.x0 = Eigen::Vector3d::Zero();
  EXPECT_EQ(SpecError("lc_truncated", wrong_size),
            "observer 'lc_truncated': x0 has 3 entries and P0 is 2×2; need 2 and 2×2");
}

}  // namespace
}  // namespace ident
