// Real-time variants of the observers: noexcept steps, zero heap allocations over 10⁴
// steps after construction (counted, including Eigen's malloc calls), the state untouched whenever a
// step is not kUpdated, and fixed-size filters that equal an independent textbook recursion.
#include <cmath>
#include <cstring>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <vector>

#include <gtest/gtest.h>

#include "ident/observers/grid_observer.h"
#include "ident/observers/kalman_filter.h"
#include "ident/observers/lc_gaussian_filter.h"
#include "ident/observers/truncated_gaussian_filter.h"
#include "ident/registry/observer_registry.h"
#include "models/measurement.h"
#include "models/state_space.h"
#include "tests/observers/linear_gaussian_data.h"
#include "tests/support/alloc_counter.h"

namespace ident {
namespace {

using testing::Model2d;

// Linear-Gaussian data y = c'x + e, e ~ N(0, r), input sin(0.3k).
struct Data {
  std::vector<StateSpaceItem> items;
};
Data Simulate(const models::LinearStateSpace& model, const Eigen::Vector2d& c, double r, int steps, unsigned seed) {
  return {testing::SimulateLinearGaussian(model, c, r, steps, seed)};
}

template <class M>
bool SameBits(const M& a, const M& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), sizeof(double) * a.size()) == 0;
}

// ------------------------------------------------------------------------------------------------
// Kalman filter, fixed-size and dynamic.

template <class F>
class KalmanRealtime : public ::testing::Test {};
using KalmanVariants = ::testing::Types<BasicKalmanFilter<2>, BasicKalmanFilter<Eigen::Dynamic>>;
TYPED_TEST_SUITE(KalmanRealtime, KalmanVariants);

TYPED_TEST(KalmanRealtime, StepsAreNoexceptAndAllocateNothingOver10kSteps) {
  const auto model = Model2d();
  const Eigen::Vector2d c(1.0, 0.5);
  const auto data = Simulate(model, c, 0.2, 10000, 3);
  TypeParam kf(model, models::GaussianMeasurement(c, 0.2), Eigen::Vector2d::Zero(), Eigen::Matrix2d::Identity());
  TypeParam twin(Eigen::Vector2d::Zero(), Eigen::Matrix2d::Identity());
  static_assert(noexcept(kf.Update(data.items[0])));
  const Eigen::Ref<const Eigen::VectorXd> u_ref(data.items[0].u), c_ref(c);  // no conversion in noexcept()
  static_assert(noexcept(kf.Predict(model, u_ref)));
  static_assert(noexcept(kf.Correct(c_ref, 0.2, 1.0)));
  typename TypeParam::StateMatrix P(2, 2);
  int updated = 0;
  {
    testing::AllocationCounter count;
    for (const auto& d : data.items) {
      updated += kf.Update(d).updated();
      updated += twin.Predict(model, d.u).updated();  // explicit Predict + scalar Correct
      updated += twin.Correct(c, 0.2, d.y).updated();
      kf.CovarianceInto(P);
    }
    EXPECT_EQ(count.allocations(), 0);
  }
  EXPECT_EQ(updated, 30000);
  EXPECT_LT((kf.mean() - twin.mean()).norm(), 1e-12);
  EXPECT_TRUE(std::isfinite(kf.log_likelihood()));
}

// Independent reference: the textbook covariance-form Kalman filter, written out here.
TYPED_TEST(KalmanRealtime, EqualsTheTextbookCovarianceFormIncludingLogLikelihood) {
  const auto model = Model2d();
  const Eigen::Vector2d c(0.7, -0.4);
  const double r = 0.3;
  const auto data = Simulate(model, c, r, 300, 5);
  Eigen::Vector2d m0(0.5, -1.0);
  Eigen::Matrix2d P0;
  P0 << 2.0, 0.3, 0.3, 1.0;
  TypeParam kf(model, models::GaussianMeasurement(c, r), m0, P0);
  Eigen::Vector2d x = m0;
  Eigen::Matrix2d P = P0;
  const Eigen::Matrix2d A = model.A, Q = model.process_noise;
  const Eigen::Vector2d B = model.B.col(0);
  double ll = 0;
  for (const auto& d : data.items) {
    ASSERT_TRUE(kf.Update(d).updated());
    x = A * x + B * d.u(0);
    P = A * P * A.transpose() + Q;
    const double s = c.dot(P * c) + r;
    const double e = d.y - c.dot(x);
    ll += -0.5 * (std::log(2 * std::numbers::pi * s) + e * e / s);
    const Eigen::Vector2d k = P * c / s;
    x += k * e;
    P -= k * k.transpose() * s;
  }
  EXPECT_LT((Eigen::Vector2d(kf.mean()) - x).norm(), 1e-10);
  EXPECT_LT((Eigen::Matrix2d(kf.covariance()) - P).norm(), 1e-12);
  EXPECT_NEAR(kf.log_likelihood(), ll, 1e-8);
}

TYPED_TEST(KalmanRealtime, RejectedOrFailedStepsLeaveTheStateBitIdentical) {
  const auto model = Model2d();
  const Eigen::Vector2d c(1.0, 0.0);
  TypeParam kf(Eigen::Vector2d(1e10, 1e10), Eigen::Matrix2d::Identity());
  kf.Predict(model, Eigen::VectorXd::Ones(1));
  kf.Correct(c, 0.5, 3.0);
  const Eigen::Vector2d x = kf.mean();
  const Eigen::Matrix2d S = kf.covariance_factor();
  const double ll = kf.log_likelihood();
  auto unchanged = [&] {
    return SameBits(Eigen::Vector2d(kf.mean()), x) && SameBits(Eigen::Matrix2d(kf.covariance_factor()), S) &&
           SameBits(Eigen::Matrix<double, 1, 1>(ll), Eigen::Matrix<double, 1, 1>(kf.log_likelihood()));
  };
  EXPECT_EQ(kf.Correct(c, 0.5, std::nan("")).status, StepStatus::kRejectedInvalid);
  EXPECT_EQ(kf.Correct(c, 0.0, 1.0).status, StepStatus::kRejectedInvalid);
  EXPECT_EQ(kf.Correct(Eigen::Vector3d::Ones(), 0.5, 1.0).status, StepStatus::kRejectedInvalid);
  EXPECT_EQ(kf.Predict(model, Eigen::VectorXd::Ones(2)).status, StepStatus::kRejectedInvalid);
  Eigen::VectorXd nan_u(1);
  nan_u(0) = std::nan("");
  EXPECT_EQ(kf.Predict(model, nan_u).status, StepStatus::kRejectedInvalid);
  models::LinearStateSpace blow_up = model;  // A x overflows to Inf
  blow_up.A = 1e300 * Eigen::Matrix2d::Identity();
  EXPECT_EQ(kf.Predict(blow_up, Eigen::VectorXd::Zero(1)).status, StepStatus::kNumericalFailure);
  const Eigen::Vector2d huge_c(-1e298, 0.0);  // y − c'x overflows
  EXPECT_EQ(kf.Correct(huge_c, 1.0, 1e308).status, StepStatus::kNumericalFailure);
  EXPECT_EQ(kf.Update({Eigen::VectorXd::Zero(1), 1.0}).status, StepStatus::kRejectedInvalid);  // no stored model
  EXPECT_TRUE(unchanged());
  // Update is all or nothing: a failing correction also undoes its prediction.
  TypeParam stored(model, models::GaussianMeasurement(huge_c, 1.0), Eigen::Vector2d(1e10, 1e10),
                   Eigen::Matrix2d::Identity());
  const Eigen::Vector2d before = stored.mean();
  EXPECT_EQ(stored.Update({Eigen::VectorXd::Zero(1), 1e308}).status, StepStatus::kNumericalFailure);
  EXPECT_TRUE(SameBits(Eigen::Vector2d(stored.mean()), before));
}

TEST(KalmanRealtime, FixedSizeFilterRejectsAPriorOfTheWrongSize) {
  EXPECT_THROW(BasicKalmanFilter<2>(Eigen::Vector3d::Zero(), Eigen::Matrix3d::Identity()), InvalidArgument);
  EXPECT_THROW(BasicLcGaussianFilter<2>(Eigen::Vector3d::Zero(), Eigen::Matrix3d::Identity()), InvalidArgument);
}

// Singular process noise (noise on the velocity only): the pivoted LDLᵀ square root must give P_N back.
TEST(KalmanRealtime, SingularProcessNoiseIsHandledExactly) {
  Eigen::MatrixXd A(2, 2), B(2, 1), Q = Eigen::MatrixXd::Zero(2, 2);
  A << 1, 0.1, 0, 1;
  B << 0.005, 0.1;
  Q(1, 1) = 0.3;
  const auto model = models::LinearStateSpace::Make(A, B, Q);
  Eigen::Matrix2d P0;
  P0 << 1.0, 0.2, 0.2, 0.5;
  BasicKalmanFilter<2> kf(Eigen::Vector2d::Zero(), P0);
  ASSERT_TRUE(kf.Predict(model, Eigen::VectorXd::Zero(1)).updated());
  const Eigen::Matrix2d expected = A * P0 * A.transpose() + Q;
  EXPECT_LT((kf.covariance() - expected).norm(), 1e-14);
}

// ------------------------------------------------------------------------------------------------
// Log-concave Gaussian filter, fixed-size and dynamic.

template <class F>
class LcGaussianRealtime : public ::testing::Test {};
using LcVariants = ::testing::Types<BasicLcGaussianFilter<2>, BasicLcGaussianFilter<Eigen::Dynamic>>;
TYPED_TEST_SUITE(LcGaussianRealtime, LcVariants);

TYPED_TEST(LcGaussianRealtime, StepsAreNoexceptAndAllocateNothingOver10kSteps) {
  // MEMS accelerometer with the threshold sensor (closed-form tilt) and a ping-pong input.
  const auto model = models::MemsAccelerometerDynamics(0.01, 1.0);
  const Eigen::Vector2d c(1.0, 0.0);
  auto sensor = std::make_shared<models::ThresholdSensor>(c, 1.0);
  const auto items = testing::SimulateThresholdSensor(model, *sensor, 10000, 7);
  Eigen::Matrix2d P0;
  P0 << 0.3, 0, 0, 1;
  TypeParam f(model, sensor, Eigen::Vector2d(0, 2), P0);
  TypeParam g(Eigen::Vector2d(0, 2), P0);
  static_assert(noexcept(f.Update(items[0])));
  static_assert(noexcept(g.Correct(*sensor, 0.0)));
  const Eigen::Ref<const Eigen::VectorXd> c_ref(c);
  const models::TiltedMoments no_tilt;
  static_assert(noexcept(g.ApplyTilt(c_ref, no_tilt)));
  const models::GaussianMeasurement gauss(c, 0.5);
  int updated = 0;
  {
    testing::AllocationCounter count;
    for (const auto& d : items) {
      updated += f.Update(d).updated();
      updated += g.Predict(model, d.u).updated();
      updated += g.Correct(gauss, d.y).updated();
    }
    EXPECT_EQ(count.allocations(), 0);
  }
  EXPECT_EQ(updated, 30000);
  EXPECT_TRUE(f.mean().allFinite() && f.covariance().allFinite());
}

// With a Gaussian measurement the exact tilt is the Kalman update: compare with the textbook recursion.
TYPED_TEST(LcGaussianRealtime, WithGaussianReadingsEqualsTheTextbookKalmanFilter) {
  const auto model = Model2d();
  const Eigen::Vector2d c(0.7, -0.4);
  const double r = 0.3;
  const auto data = Simulate(model, c, r, 300, 9);
  TypeParam f(model, std::make_shared<models::GaussianMeasurement>(c, r), Eigen::Vector2d::Zero(),
              Eigen::Matrix2d::Identity());
  Eigen::Vector2d x = Eigen::Vector2d::Zero();
  Eigen::Matrix2d P = Eigen::Matrix2d::Identity();
  for (const auto& d : data.items) {
    ASSERT_TRUE(f.Update(d).updated());
    x = model.A * x + model.B * d.u;
    P = model.A * P * model.A.transpose() + model.process_noise;
    const double s = c.dot(P * c) + r;
    const Eigen::Vector2d k = P * c / s;
    x += k * (d.y - c.dot(x));
    P -= k * k.transpose() * s;
  }
  EXPECT_LT((Eigen::Vector2d(f.mean()) - x).norm(), 1e-10);
  EXPECT_LT((Eigen::Matrix2d(f.covariance()) - P).norm(), 1e-12);
}

// ScaleAndApplyTilt (the lc:* regression's step under forgetting) is ScaleCovariance then ApplyTilt, in
// one pass, and keeps P exactly symmetric.
TYPED_TEST(LcGaussianRealtime, ScaleAndApplyTiltIsTheTimeUpdateThenTheTilt) {
  Eigen::Matrix2d P0;
  P0 << 0.7, 0.2, 0.2, 0.4;
  TypeParam one(Eigen::Vector2d(0.3, -1), P0), two(Eigen::Vector2d(0.3, -1), P0);
  std::mt19937_64 rng(3);
  std::normal_distribution<double> g;
  for (int t = 0; t < 500; ++t) {
    const Eigen::Vector2d c(g(rng), 1 + g(rng));
    const double factor = 1 / 0.95, s2 = factor * c.dot(one.covariance() * c), prior = c.dot(one.mean());
    // The tilt of a Gaussian reading y = c'x + N(0, 0.2²): mean and variance of the product of Gaussians.
    const double y = prior + g(rng), r2 = 0.04, v = s2 * r2 / (s2 + r2);
    const models::TiltedMoments tilt{0.0, v * (prior / s2 + y / r2), v, true};
    const Eigen::Vector2d Pc = one.covariance() * c;
    ASSERT_TRUE(one.ScaleAndApplyTilt(factor, c, Pc, tilt).updated());
    ASSERT_TRUE(two.ScaleCovariance(factor).updated());
    ASSERT_TRUE(two.ApplyTilt(c, tilt).updated());
    ASSERT_EQ(one.covariance()(0, 1), one.covariance()(1, 0)) << t;
  }
  EXPECT_LT((one.mean() - two.mean()).norm(), 1e-12 * two.mean().norm());
  EXPECT_LT((one.covariance() - two.covariance()).norm(), 1e-12 * two.covariance().norm());
}

// A measurement function whose tilt throws (user code, or a Boost.Math overflow error).
class ThrowingMeasurement final : public models::ProjectedMeasurement {
 public:
  ThrowingMeasurement() : ProjectedMeasurement(Eigen::Vector2d(1, 0)) {}
  std::string name() const override { return "throwing"; }
  double LogLikelihoodScalar(double, double) const override { return 0; }
  double ScalarStrength(double) const override { return 0; }
  bool IsValidOutput(double) const override { return true; }
  models::TiltedMoments Tilt(double, double, double) const override { throw std::overflow_error("boom"); }
};

TYPED_TEST(LcGaussianRealtime, RejectedOrFailedStepsLeaveTheStateBitIdentical) {
  const auto model = models::MemsAccelerometerDynamics(0.01, 1.0);
  const Eigen::Vector2d c(1.0, 0.0);
  models::ThresholdSensor sensor(c, 1.0);
  TypeParam f(Eigen::Vector2d(0, 1), 0.01 * Eigen::Matrix2d::Identity());
  f.Predict(model, Eigen::VectorXd::Zero(1));
  f.Correct(sensor, 0.0);
  const Eigen::Vector2d m = f.mean();
  const Eigen::Matrix2d P = f.covariance();
  const double ll = f.log_likelihood();
  auto unchanged = [&] {
    return SameBits(Eigen::Vector2d(f.mean()), m) && SameBits(Eigen::Matrix2d(f.covariance()), P) &&
           SameBits(Eigen::Matrix<double, 1, 1>(ll), Eigen::Matrix<double, 1, 1>(f.log_likelihood()));
  };
  EXPECT_EQ(f.Correct(sensor, 0.5).status, StepStatus::kRejectedInvalid);  // not a sensor output
  EXPECT_EQ(f.Correct(sensor, std::nan("")).status, StepStatus::kRejectedInvalid);
  EXPECT_EQ(f.Correct(ThrowingMeasurement(), 0.0).status, StepStatus::kNumericalFailure);
  EXPECT_EQ(f.ApplyTilt(c, models::TiltedMoments{}).status, StepStatus::kNumericalFailure);  // ok = false
  EXPECT_EQ(f.ApplyTilt(Eigen::Vector3d::Ones(), {0.0, 0.0, 1.0, true}).status, StepStatus::kRejectedInvalid);
  EXPECT_EQ(f.ApplyTilt(Eigen::Vector2d::Zero(), {0.0, 0.0, 1.0, true}).status, StepStatus::kNumericalFailure);
  EXPECT_EQ(f.Predict(model, Eigen::VectorXd::Ones(3)).status, StepStatus::kRejectedInvalid);
  models::LinearStateSpace blow_up = model;
  blow_up.A = 1e300 * Eigen::Matrix2d::Identity();
  EXPECT_EQ(f.Predict(blow_up, Eigen::VectorXd::Zero(1)).status, StepStatus::kNumericalFailure);  // P overflows
  EXPECT_EQ(f.Update({Eigen::VectorXd::Zero(1), 0.0}).status, StepStatus::kRejectedInvalid);      // no model
  const Eigen::Vector2d Pc = P * c;
  EXPECT_EQ(f.ScaleAndApplyTilt(0.5, c, Pc, {0.0, 0.0, 1.0, true}).status, StepStatus::kRejectedInvalid);
  EXPECT_EQ(f.ScaleAndApplyTilt(1.1, c, Pc, models::TiltedMoments{}).status, StepStatus::kNumericalFailure);
  const Eigen::Vector2d tiny = 1e-10 * c, P_tiny = 1e-10 * Pc;  // gain ~1e10: the mean would overflow
  EXPECT_EQ(f.ScaleAndApplyTilt(1.1, tiny, P_tiny, {0.0, 1e300, 0.0, true}).status, StepStatus::kNumericalFailure);
  EXPECT_TRUE(unchanged());
  TypeParam wide(Eigen::Vector2d::Zero(), 10 * Eigen::Matrix2d::Identity());  // 1e308·P would overflow
  EXPECT_EQ(wide.ScaleAndApplyTilt(1e308, c, Eigen::Vector2d(10, 0), {0.0, 0.0, 1.0, true}).status,
            StepStatus::kNumericalFailure);
  EXPECT_TRUE(SameBits(Eigen::Matrix2d(wide.covariance()), Eigen::Matrix2d(10 * Eigen::Matrix2d::Identity())));
  // Update is all or nothing.
  TypeParam stored(model, std::make_shared<ThrowingMeasurement>(), Eigen::Vector2d(0, 1), Eigen::Matrix2d::Identity());
  EXPECT_EQ(stored.Update({Eigen::VectorXd::Zero(1), 0.0}).status, StepStatus::kNumericalFailure);
  EXPECT_TRUE(SameBits(Eigen::Vector2d(stored.mean()), Eigen::Vector2d(0, 1)));
  EXPECT_TRUE(SameBits(Eigen::Matrix2d(stored.covariance()), Eigen::Matrix2d(Eigen::Matrix2d::Identity())));
}

// ------------------------------------------------------------------------------------------------
// Assumed-density filter on the reading's interval (lc_truncated): fixed-size state, no workspace.

TEST(TruncatedGaussianRealtime, UpdateAllocatesNothingOver10kSteps) {
  const auto model = models::MemsAccelerometerDynamics(0.01, 1.0);
  const models::ThresholdSensor sensor(Eigen::Vector2d(1, 0), 1.0);
  const auto items = testing::SimulateThresholdSensor(model, sensor, 10000, 7);
  Eigen::Matrix2d P0;
  P0 << 0.3, 0, 0, 1;
  TruncatedGaussianFilter f(model, sensor, Eigen::Vector2d(0, 2), P0);
  const ObserverProblem problem{model, std::make_shared<models::ThresholdSensor>(sensor), Eigen::Vector2d(0, 2), P0};
  auto registered = MakeStateObserver(ParseEstimatorSpec("lc_truncated"), problem);
  int updated = 0, events = 0;
  {
    testing::AllocationCounter count;
    for (const auto& d : items) {
      updated += f.Update(d).updated();
      updated += registered->Update(d).updated();  // through AnyStateObserver
      events += d.y != 0;
    }
    EXPECT_EQ(count.allocations(), 0);
  }
  EXPECT_EQ(updated, 20000);
  EXPECT_GT(events, 100);  // many ±1 readings: changes of reading and repeated ±1, not only y = 0
  EXPECT_TRUE(f.mean().allFinite() && f.covariance().allFinite());
}

TEST(TruncatedGaussianRealtime, RejectedItemsLeaveTheStateBitIdentical) {
  const auto model = models::MemsAccelerometerDynamics(0.01, 1.0);
  const models::ThresholdSensor sensor(Eigen::Vector2d(1, 0), 1.0);
  TruncatedGaussianFilter f(model, sensor, Eigen::Vector2d(0.5, 1), 0.01 * Eigen::Matrix2d::Identity());
  ASSERT_TRUE(f.Update({Eigen::VectorXd::Zero(1), 0.0}).updated());
  ASSERT_TRUE(f.Update({Eigen::VectorXd::Constant(1, 3.0), 0.0}).updated());
  const Eigen::Vector2d m = f.mean(), pm = f.parent_mean();
  const Eigen::Matrix2d P = f.covariance(), pP = f.parent_covariance();
  auto unchanged = [&] {
    return SameBits(f.mean(), m) && SameBits(f.covariance(), P) && SameBits(f.parent_mean(), pm) &&
           SameBits(f.parent_covariance(), pP);
  };
  EXPECT_EQ(f.Update({Eigen::VectorXd::Zero(2), 0.0}).status, StepStatus::kRejectedInvalid);  // u of wrong size
  EXPECT_EQ(f.Update({Eigen::VectorXd(), 0.0}).status, StepStatus::kRejectedInvalid);
  EXPECT_EQ(f.Update({Eigen::VectorXd::Constant(1, std::nan("")), 0.0}).status, StepStatus::kRejectedInvalid);
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_EQ(f.Update({Eigen::VectorXd::Constant(1, inf), 0.0}).status, StepStatus::kRejectedInvalid);
  EXPECT_EQ(f.Update({Eigen::VectorXd::Zero(1), 0.5}).status, StepStatus::kRejectedInvalid);  // not a reading
  EXPECT_EQ(f.Update({Eigen::VectorXd::Zero(1), std::nan("")}).status, StepStatus::kRejectedInvalid);
  EXPECT_EQ(f.Update({Eigen::VectorXd::Zero(1), 2.0}).status, StepStatus::kRejectedInvalid);
  EXPECT_TRUE(unchanged());
  EXPECT_EQ(f.failures(), 0);
  // Without a stored model Update() refuses every item.
  TruncatedGaussianFilter no_model(sensor, m, P);
  EXPECT_EQ(no_model.Update({Eigen::VectorXd::Zero(1), 0.0}).status, StepStatus::kRejectedInvalid);
  EXPECT_TRUE(SameBits(no_model.mean(), m) && SameBits(no_model.covariance(), P));
  // A model that is not 2-state is refused at construction.
  const auto three = models::LinearStateSpace::Make(Eigen::MatrixXd::Identity(3, 3), Eigen::MatrixXd::Zero(3, 1),
                                                    Eigen::MatrixXd::Identity(3, 3));
  EXPECT_THROW(TruncatedGaussianFilter(three, sensor, m, P), InvalidArgument);
}

// ------------------------------------------------------------------------------------------------
// Grid observer: FFT plans and buffers are built at construction and reused by every step.

TEST(GridObserverRealtime, StepsAllocateNothingAfterConstruction) {
  for (const int dim : {1, 2}) {
    const auto mems = models::MemsAccelerometerDynamics(0.01, 1.0);
    models::LinearStateSpace model = mems;
    Eigen::VectorXd c = Eigen::VectorXd::Unit(dim, 0);
    if (dim == 1)
      model =
          models::LinearStateSpace::Make(Eigen::MatrixXd::Constant(1, 1, 0.99), Eigen::MatrixXd::Constant(1, 1, 0.1),
                                         Eigen::MatrixXd::Constant(1, 1, 0.01));
    auto sensor = std::make_shared<models::ThresholdSensor>(c, 1.0);
    GridObserverOptions opt;
    opt.points.assign(dim, 32);
    GridObserver grid(model, sensor, Eigen::VectorXd::Zero(dim), 0.3 * Eigen::MatrixXd::Identity(dim, dim), opt);
    std::vector<StateSpaceItem> items;
    for (int k = 0; k < 300; ++k)
      items.push_back({Eigen::VectorXd::Constant(1, std::sin(0.05 * k)), k % 50 == 0 ? 1.0 : 0.0});
    int updated = 0;
    {
      testing::AllocationCounter count;
      for (const auto& d : items) updated += grid.Update(d).updated();
      EXPECT_EQ(count.allocations(), 0) << dim << "-D";
    }
    EXPECT_GT(updated, 250) << dim << "-D";
  }
}

}  // namespace
}  // namespace ident
