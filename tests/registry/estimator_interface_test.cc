// The one estimator interface (common/estimator.h) and the one registry (ident/registry/estimator_registry.h):
// regression estimators and state observers are built by name from one spec syntax and driven through
// AnyEstimator alone. Checked against independent computations: RLS through the interface against the Kalman
// filter of the same regression through the interface, an observer's Predict and mean against a dense Kalman
// filter written out here, a regression's Predict against its own step's prediction error; Reset against a
// fresh run; every refusal names what is wrong.
#include <cmath>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Dense>

#include "common/error.h"
#include "common/estimator.h"
#include "ident/registry/estimator_registry.h"
#include "tests/observers/linear_gaussian_data.h"
#include "tests/registry/spec_error.h"

namespace ident {
namespace {

#define EXPECT_CONTAINS(what, part) EXPECT_NE(std::string(what).find(part), std::string::npos) << (what)

ObserverProblem TwoStateGaussianProblem() {
  return {testing::Model2d(), std::make_shared<models::GaussianMeasurement>(Eigen::Vector2d(1.0, 0.5), 0.2),
          Eigen::Vector2d(0.0, 0.0), Eigen::Matrix2d::Identity()};
}

// Regression data y = z'θ + e, e ~ N(0, 0.3²), z ~ N(0, I), seeded.
struct RegressionData {
  std::vector<Eigen::VectorXd> z;
  std::vector<double> y;
};

RegressionData SimulateRegression(const Eigen::VectorXd& theta, int n, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal;
  RegressionData d;
  for (int t = 0; t < n; ++t) {
    Eigen::VectorXd z(theta.size());
    for (Eigen::Index i = 0; i < z.size(); ++i) z(i) = normal(rng);
    d.z.push_back(z);
    d.y.push_back(z.dot(theta) + 0.3 * normal(rng));
  }
  return d;
}

using testing::SpecError;

TEST(EstimatorInterface, OneRegistryNamesEveryEstimatorAndObserver) {
  EXPECT_EQ(EstimatorNames(), (std::vector<std::string>{"rls", "cauchy", "student", "huber", "cauchy-ml", "lc",
                                                        "kalman", "lc_gaussian", "lc_truncated", "grid"}));
  EXPECT_EQ(EstimatorItemKind("student"), ItemKind::kRegression);
  EXPECT_EQ(EstimatorItemKind("grid"), ItemKind::kStateSpace);
  EXPECT_THROW(EstimatorItemKind("kalmann"), InvalidArgument);
  auto rls = MakeEstimator(ParseEstimatorSpec("rls"), RegressionProblem{3});
  auto grid = MakeEstimator(ParseEstimatorSpec("grid:points=32"), TwoStateGaussianProblem());
  EXPECT_EQ(rls->item_kind(), ItemKind::kRegression);
  EXPECT_EQ(rls->dimension(), 3);
  EXPECT_EQ(grid->item_kind(), ItemKind::kStateSpace);
  EXPECT_EQ(grid->dimension(), 2);
}

// RLS on items (y, z) with z = c every time is the Kalman filter of the state θ (A = I, no process noise) read
// through y = c'θ + e. RLS's prior information ν0·V0_z = 1e-2·I about Θ0 = 0 is σ²P0⁻¹ of the filter; the
// design c c' is singular, so the prior decides the unobserved direction in both alike (the square-root and
// the LD forms then differ by a few 1e-12 relative after 200 steps).
TEST(EstimatorInterface, RlsIsTheKalmanFilterOfItsRegressionThroughTheInterface) {
  const Eigen::Vector2d c(0.8, -1.3);
  const double sigma = 0.4, info = 1e-2;
  EstimatorSettings rls_settings = ParseEstimatorSpec("rls");
  rls_settings.prior = RegressionPrior::Diagonal(2, 1.0, 1.0, info);
  std::unique_ptr<AnyEstimator> rls = MakeEstimator(rls_settings, RegressionProblem{2});
  const ObserverProblem regression_as_state_space{
      models::LinearStateSpace::Make(Eigen::Matrix2d::Identity(), Eigen::MatrixXd(2, 0), Eigen::Matrix2d::Zero()),
      std::make_shared<models::GaussianMeasurement>(c, sigma * sigma), Eigen::Vector2d::Zero(),
      sigma * sigma / info * Eigen::Matrix2d::Identity()};
  std::unique_ptr<AnyEstimator> kalman = MakeEstimator(ParseEstimatorSpec("kalman"), regression_as_state_space);
  std::mt19937_64 rng(11);
  std::normal_distribution<double> normal;
  for (int t = 0; t < 200; ++t) {
    const double y = c.dot(Eigen::Vector2d(2.0, 0.5)) + sigma * normal(rng);
    const RegressionItem regression_item{y, c};
    const StateSpaceItem state_space_item{Eigen::VectorXd(0), y};
    EXPECT_NEAR(rls->Predict(regression_item), kalman->Predict(state_space_item), 1e-12 * (1 + std::abs(y)));
    ASSERT_TRUE(rls->Update(regression_item).updated());
    ASSERT_TRUE(kalman->Update(state_space_item).updated());
    if (t == 0 || t == 9 || t == 199) {
      EXPECT_LE((rls->mean() - kalman->mean()).norm(), 1e-11 * kalman->mean().norm()) << "after " << t + 1;
    }
  }
}

// An observer's Predict is c'(A x̂ + B u) and its mean follows the Kalman recursion: both against a dense
// Kalman filter (covariance form) written out here.
TEST(EstimatorInterface, ObserverPredictIsTheKalmanPredictedReading) {
  const ObserverProblem problem = TwoStateGaussianProblem();
  const Eigen::Vector2d c(1.0, 0.5);
  const double r = 0.2;
  const auto items = testing::SimulateLinearGaussian(problem.model, c, r, 80, 5);
  for (const char* spec : {"kalman", "lc_gaussian"}) {
    std::unique_ptr<AnyEstimator> observer = MakeEstimator(ParseEstimatorSpec(spec), problem);
    Eigen::Vector2d x = problem.x0;
    Eigen::Matrix2d P = problem.P0;
    for (const StateSpaceItem& item : items) {
      x = problem.model.A * x + problem.model.B * item.u;
      P = problem.model.A * P * problem.model.A.transpose() + problem.model.process_noise;
      EXPECT_NEAR(observer->Predict(item), c.dot(x), 1e-10 * (1 + std::abs(c.dot(x)))) << spec;
      const double s = c.dot(P * c) + r;
      const Eigen::Vector2d gain = P * c / s;
      x += gain * (item.y - c.dot(x));
      P -= gain * c.transpose() * P;
      ASSERT_TRUE(observer->Update(item).updated()) << spec;
    }
    EXPECT_LE((observer->mean() - x).norm(), 1e-9 * x.norm()) << spec;
    EXPECT_LE((observer->covariance() - P).norm(), 1e-9 * P.norm()) << spec;
  }
}

// A regression estimator's Predict(d) before its update is what the update then reports as its prediction:
// y − Predict(d) = ê(t).
TEST(EstimatorInterface, RegressionPredictIsTheStepsPrediction) {
  const RegressionData d = SimulateRegression(Eigen::Vector3d(1.0, -0.5, 2.0), 300, 3);
  for (const char* spec : {"rls", "cauchy", "student:3", "lc:laplace"}) {
    std::unique_ptr<AnyEstimator> est = MakeEstimator(ParseEstimatorSpec(spec), RegressionProblem{3});
    int checked = 0;
    for (std::size_t t = 0; t < d.y.size(); ++t) {
      const RegressionItem item{d.y[t], d.z[t]};
      const double predicted = est->Predict(item);
      EXPECT_NEAR(predicted, est->mean().dot(d.z[t]), 1e-12 * (1 + std::abs(predicted))) << spec;
      const StepReport report = est->Update(item);
      if (report.updated() && std::isfinite(report.prediction_error) && t >= 100) {
        EXPECT_NEAR(d.y[t] - predicted, report.prediction_error, 1e-9 * (1 + std::abs(d.y[t]))) << spec << " t " << t;
        ++checked;
      }
    }
    EXPECT_GE(checked, 150) << spec;
    EXPECT_LE((est->mean() - Eigen::Vector3d(1.0, -0.5, 2.0)).norm(), 0.1) << spec;
  }
}

// An item of the other kind is refused, the state untouched; its prediction is NaN.
TEST(EstimatorInterface, AnItemOfTheOtherKindIsRefused) {
  auto rls = MakeEstimator(ParseEstimatorSpec("rls"), RegressionProblem{2});
  auto kalman = MakeEstimator(ParseEstimatorSpec("kalman"), TwoStateGaussianProblem());
  const Eigen::Vector2d z(1.0, 2.0);
  ASSERT_TRUE(rls->Update(RegressionItem{1.0, z}).updated());
  const Eigen::VectorXd rls_before = rls->mean();
  const Eigen::VectorXd kalman_before = kalman->mean();
  const StateSpaceItem state_space_item{Eigen::VectorXd::Constant(1, 0.5), 1.0};
  EXPECT_EQ(rls->Update(state_space_item).status, StepStatus::kRejectedInvalid);
  EXPECT_EQ(kalman->Update(RegressionItem{1.0, z}).status, StepStatus::kRejectedInvalid);
  EXPECT_TRUE(std::isnan(rls->Predict(state_space_item)));
  EXPECT_TRUE(std::isnan(kalman->Predict(RegressionItem{1.0, z})));
  EXPECT_EQ(rls->mean(), rls_before);
  EXPECT_EQ(kalman->mean(), kalman_before);
  // An input of the wrong size: no prediction.
  EXPECT_TRUE(std::isnan(kalman->Predict(StateSpaceItem{Eigen::VectorXd(0), 1.0})));
}

// Reset returns to the prior: the same items then give bit-identical estimates.
TEST(EstimatorInterface, ResetRunsAgainFromThePrior) {
  const RegressionData d = SimulateRegression(Eigen::Vector3d(0.5, 1.0, -1.0), 250, 9);
  for (const char* spec : {"rls", "cauchy", "student:3", "lc:huber", "rls:forgetting=0.98"}) {
    auto est = MakeEstimator(ParseEstimatorSpec(spec), RegressionProblem{3});
    const Eigen::VectorXd prior = est->mean();
    for (std::size_t t = 0; t < d.y.size(); ++t) est->Update(RegressionItem{d.y[t], d.z[t]});
    const Eigen::VectorXd first = est->mean();
    const Eigen::MatrixXd first_cov = est->covariance();
    est->Reset();
    EXPECT_EQ(est->mean(), prior) << spec;
    for (std::size_t t = 0; t < d.y.size(); ++t) est->Update(RegressionItem{d.y[t], d.z[t]});
    EXPECT_EQ(est->mean(), first) << spec;
    EXPECT_EQ(est->covariance(), first_cov) << spec;
  }
  const ObserverProblem problem = TwoStateGaussianProblem();
  const auto items = testing::SimulateLinearGaussian(problem.model, Eigen::Vector2d(1.0, 0.5), 0.2, 40, 2);
  for (const char* spec : {"kalman", "lc_gaussian", "grid:points=24"}) {
    auto obs = MakeEstimator(ParseEstimatorSpec(spec), problem);
    const Eigen::VectorXd prior = obs->mean();
    for (const auto& item : items) obs->Update(item);
    const Eigen::VectorXd first = obs->mean();
    obs->Reset();
    EXPECT_EQ(obs->mean(), prior) << spec;
    for (const auto& item : items) obs->Update(item);
    EXPECT_EQ(obs->mean(), first) << spec;
  }
}

// One spec syntax: the typed keys mean what the typed fields mean.
TEST(EstimatorInterface, OneOptionsMechanism) {
  const RegressionData d = SimulateRegression(Eigen::Vector3d(1.0, 2.0, 3.0), 200, 4);
  auto run = [&](const EstimatorSettings& s) {
    auto est = MakeEstimator(s, RegressionProblem{3});
    for (std::size_t t = 0; t < d.y.size(); ++t) est->Update(RegressionItem{d.y[t], d.z[t]});
    return Eigen::VectorXd(est->mean());
  };
  EstimatorSettings typed = ParseEstimatorSpec("rls");
  typed.forgetting.factor = 0.97;
  EXPECT_EQ(run(ParseEstimatorSpec("rls:forgetting=0.97")), run(typed));
  EXPECT_EQ(run(ParseEstimatorSpec("student:dof=3")), run(ParseEstimatorSpec("student:3")));
  EXPECT_EQ(run(ParseEstimatorSpec("student:k=3")), run(ParseEstimatorSpec("student:3")));
  typed = ParseEstimatorSpec("cauchy");
  typed.lock_in.window = 150;
  EXPECT_EQ(run(ParseEstimatorSpec("cauchy:lock_in_window=150")), run(typed));
  EXPECT_EQ(ParseEstimatorSpec("grid:points=64x48,noise_sigmas=5").options,
            (std::map<std::string, std::string>{{"points", "64x48"}, {"noise_sigmas", "5"}}));

  const RegressionProblem regression{3};
  const ObserverProblem observer = TwoStateGaussianProblem();
  EXPECT_CONTAINS(SpecError("rls:points=3", regression),
                  "estimator 'rls' has no option 'points' (options: forgetting)");
  EXPECT_CONTAINS(SpecError("huber:window=3", regression),
                  "estimator 'huber' has no option 'window' (it takes no options)");
  EXPECT_CONTAINS(SpecError("rls:forgetting=fast", regression), "option forgetting = 'fast' is not a finite number");
  EXPECT_CONTAINS(SpecError("student:dof=3,k=4", regression), "option k given twice");
  EXPECT_CONTAINS(SpecError("student:dof=3,", regression), "ends with ','");
  EXPECT_CONTAINS(SpecError("student:3,", regression), "'3' is not key=value");
  EXPECT_CONTAINS(SpecError("rls:", regression), "ends with ':'");
  EXPECT_CONTAINS(SpecError("grid:forgetting=0.9", observer), "forgetting does not apply to observer 'grid'");
  EXPECT_CONTAINS(SpecError("kalman:dof=3", observer), "dof does not apply to observer 'kalman'");
  EXPECT_CONTAINS(SpecError("kalman", regression), "'kalman' is a state observer");
  EXPECT_CONTAINS(SpecError("rls", observer), "'rls' is a regression estimator");
  EXPECT_CONTAINS(SpecError("kalmann", regression), "unknown estimator 'kalmann'");
  EXPECT_THROW(RegisterRegressionEstimator(
                   "grid", [](const EstimatorSettings&, int) { return std::unique_ptr<AnyRegressionEstimator>(); }),
               InvalidArgument);
}

}  // namespace
}  // namespace ident
