// Linear-Gaussian cross-agreement: square-root Kalman filter against a textbook covariance Kalman
// filter and the batch joint-Gaussian likelihood; log-concave Gaussian filter and grid observer
// against the Kalman filter.
#include <cmath>
#include <numbers>
#include <random>

#include <gtest/gtest.h>
#include <Eigen/Cholesky>
#include <Eigen/LU>

#include "common/dense_decompositions.h"
#include "common/error.h"
#include "ident/observers/grid_observer.h"
#include "ident/observers/kalman_filter.h"
#include "ident/observers/lc_gaussian_filter.h"
#include "models/measurement.h"
#include "models/state_space.h"
#include "tests/observers/linear_gaussian_data.h"

namespace ident {
namespace {

struct Sim {
  std::vector<Eigen::VectorXd> u;
  std::vector<double> y;
};

Sim Simulate(const models::LinearStateSpace& model, const Eigen::VectorXd& c, double r, int steps, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal;
  const int n = model.num_states();
  const Eigen::MatrixXd L = dense::Llt(model.process_noise + 1e-300 * Eigen::MatrixXd::Identity(n, n)).matrixL();
  Eigen::VectorXd x = Eigen::VectorXd::Zero(n), w(n);
  Sim s;
  for (int k = 0; k < steps; ++k) {
    Eigen::VectorXd u(model.num_inputs());
    for (int i = 0; i < u.size(); ++i) u(i) = std::sin(0.3 * k + i);
    for (int i = 0; i < n; ++i) w(i) = normal(rng);
    x = model.A * x + model.B * u + L * w;
    s.u.push_back(u);
    s.y.push_back(c.dot(x) + std::sqrt(r) * normal(rng));
  }
  return s;
}

using testing::Model2d;

TEST(KalmanFilter, SquareRootFormMatchesTextbookCovarianceFormAndBatchLikelihood) {
  const auto model = Model2d();
  const Eigen::Vector2d c(1.0, 0.5);
  const double r = 0.3;
  const int steps = 12;
  const Sim sim = Simulate(model, c, r, steps, 11);
  Eigen::Vector2d x0(0.2, -0.1);
  Eigen::Matrix2d P0;
  P0 << 1.0, 0.3, 0.3, 0.5;
  KalmanFilter kf(model, models::GaussianMeasurement(c, r), x0, P0);
  Eigen::VectorXd x = x0;
  Eigen::MatrixXd P = P0;
  for (int k = 0; k < steps; ++k) {
    ASSERT_TRUE(kf.Update({sim.u[k], sim.y[k]}).updated());
    x = model.A * x + model.B * sim.u[k];  // textbook form
    P = model.A * P * model.A.transpose() + model.process_noise;
    const double s = c.dot(P * c) + r;
    const Eigen::VectorXd K = P * c / s;
    x += K * (sim.y[k] - c.dot(x));
    P -= K * K.transpose() * s;
    EXPECT_LT((kf.mean() - x).norm(), 1e-12);
    EXPECT_LT((kf.covariance() - P).norm(), 1e-12);
  }
  // Batch: y_{1:T} is jointly Gaussian; its mean and covariance from the model by brute force.
  const int n = 2;
  Eigen::MatrixXd Phi = Eigen::MatrixXd::Identity(n, n);  // x_k = Phi_k x0 + drift_k + Σ_j Psi_kj v_j
  std::vector<Eigen::MatrixXd> Psi;                       // Psi[j] for current k
  Eigen::VectorXd drift = Eigen::VectorXd::Zero(n), ymean(steps);
  std::vector<Eigen::MatrixXd> rows_x0(steps), rows_v(steps);
  Eigen::MatrixXd Ycov(steps, steps);
  std::vector<std::vector<Eigen::MatrixXd>> psi_all;
  for (int k = 0; k < steps; ++k) {
    Phi = model.A * Phi;
    drift = model.A * drift + model.B * sim.u[k];
    for (auto& p : Psi) p = model.A * p;
    Psi.push_back(Eigen::MatrixXd::Identity(n, n));
    psi_all.push_back(Psi);
    ymean(k) = c.dot(Phi * x0 + drift);
    rows_x0[k] = c.transpose() * Phi;
  }
  for (int k = 0; k < steps; ++k)
    for (int l = 0; l < steps; ++l) {
      double v = (rows_x0[k] * P0 * rows_x0[l].transpose())(0, 0) + (k == l ? r : 0.0);
      for (int j = 0; j <= std::min(k, l); ++j)
        v += c.dot(psi_all[k][j] * model.process_noise * psi_all[l][j].transpose() * c);
      Ycov(k, l) = v;
    }
  Eigen::VectorXd e(steps);
  for (int k = 0; k < steps; ++k) e(k) = sim.y[k] - ymean(k);
  const Eigen::LLT<Eigen::MatrixXd> llt = dense::Llt(Ycov);
  const Eigen::MatrixXd Lc = llt.matrixL();
  const double log_det = 2 * Lc.diagonal().array().log().sum();
  const double batch = -0.5 * (steps * std::log(2 * std::numbers::pi) + log_det + e.dot(llt.solve(e)));
  EXPECT_NEAR(kf.log_likelihood(), batch, 1e-9);
}

TEST(KalmanFilter, RejectsBadInputWithClearErrors) {
  EXPECT_THROW(KalmanFilter(Eigen::Vector2d::Zero(), Eigen::Matrix2d::Zero()), InvalidArgument);
  EXPECT_THROW(KalmanFilter(Eigen::Vector2d::Zero(), Eigen::Matrix3d::Identity()), InvalidArgument);
  KalmanFilter kf(Eigen::Vector2d::Zero(), Eigen::Matrix2d::Identity());
  EXPECT_EQ(kf.Predict(Model2d(), Eigen::VectorXd::Zero(3)).status, StepStatus::kRejectedInvalid);
  EXPECT_EQ(kf.Correct(Eigen::Vector2d(1, 0), -1.0, 0.0).status, StepStatus::kRejectedInvalid);
}

TEST(LcGaussianFilter, WithGaussianMeasurementEqualsKalmanFilter) {
  const auto model = Model2d();
  const Eigen::Vector2d c(1.0, 0.5);
  const Sim sim = Simulate(model, c, 0.3, 200, 12);
  auto meas = std::make_shared<models::GaussianMeasurement>(c, 0.3);
  KalmanFilter kf(model, *meas, Eigen::Vector2d::Zero(), Eigen::Matrix2d::Identity());
  LcGaussianFilter lc(model, meas, Eigen::Vector2d::Zero(), Eigen::Matrix2d::Identity());
  for (int k = 0; k < 200; ++k) {
    kf.Update({sim.u[k], sim.y[k]});
    lc.Update({sim.u[k], sim.y[k]});
    ASSERT_LT((kf.mean() - lc.mean()).norm(), 1e-10);
    ASSERT_LT((kf.covariance() - lc.covariance()).norm(), 1e-10);
  }
  EXPECT_NEAR(kf.log_likelihood(), lc.log_likelihood(), 1e-8);
}

// Grid vs Kalman. Stated discretisation error: means within 0.5 Δ and covariances within a few Δ²
// (linear interpolation smooths by ≤ Δ²/4 per step; measurements keep the accumulated error bounded).
void ExpectGridAgreesWithKalman(const models::LinearStateSpace& model, const Eigen::VectorXd& c, int points,
                                unsigned seed) {
  const int n = model.num_states();
  const double r = 0.3;
  const int steps = 60;
  const Sim sim = Simulate(model, c, r, steps, seed);
  auto meas = std::make_shared<models::GaussianMeasurement>(c, r);
  const Eigen::VectorXd m0 = Eigen::VectorXd::Zero(n);
  const Eigen::MatrixXd P0 = Eigen::MatrixXd::Identity(n, n);
  KalmanFilter kf(model, *meas, m0, P0);
  GridObserverOptions opt;
  opt.points.assign(n, points);
  GridObserver grid(model, meas, m0, P0, opt);
  double max_mean_err = 0, max_cov_err = 0;
  for (int k = 0; k < steps; ++k) {
    kf.Update({sim.u[k], sim.y[k]});
    ASSERT_TRUE(grid.Update({sim.u[k], sim.y[k]}).updated());
    double d2 = 0, dmax = 0;
    for (int i = 0; i < n; ++i) {
      d2 = std::max(d2, grid.spacing(i) * grid.spacing(i));
      dmax = std::max(dmax, grid.spacing(i));
    }
    const Eigen::MatrixXd P = kf.covariance();
    max_mean_err = std::max(max_mean_err, (grid.mean() - kf.mean()).cwiseAbs().maxCoeff() / dmax);
    max_cov_err = std::max(max_cov_err, (grid.covariance() - P).cwiseAbs().maxCoeff() / d2);
  }
  EXPECT_LT(max_mean_err, 0.5) << "in grid spacings";
  EXPECT_LT(max_cov_err, 3.0) << "in squared grid spacings";
}

TEST(GridObserver, AgreesWithKalmanFilterIn1D) {
  Eigen::MatrixXd A(1, 1), B(1, 1), Q(1, 1);
  A << 0.9;
  B << 0.5;
  Q << 0.2;
  ExpectGridAgreesWithKalman(models::LinearStateSpace::Make(A, B, Q), Eigen::VectorXd::Ones(1), 256, 3);
}

TEST(GridObserver, AgreesWithKalmanFilterIn2D) {
  ExpectGridAgreesWithKalman(Model2d(), Eigen::Vector2d(1.0, 0.5), 96, 4);
}

TEST(GridObserver, AgreesWithKalmanFilterIn3D) {
  Eigen::MatrixXd A(3, 3), B(3, 1), Q = 0.05 * Eigen::MatrixXd::Identity(3, 3);
  A << 0.9, 0.1, 0, 0, 0.8, 0.2, 0.1, 0, 0.85;
  B << 0, 0, 1;
  ExpectGridAgreesWithKalman(models::LinearStateSpace::Make(A, B, Q), Eigen::Vector3d(1, 0, 0.5), 24, 5);
}

TEST(GridObserver, SampledNoiseDensityMatchesCharacteristicFunctionPath) {
  // The same Gaussian process noise given as a log density (sampled kernel) and analytically.
  const auto model = Model2d();
  const Eigen::Vector2d c(1.0, 0.5);
  auto meas = std::make_shared<models::GaussianMeasurement>(c, 0.3);
  const Sim sim = Simulate(model, c, 0.3, 20, 6);
  GridObserverOptions opt;
  opt.points = {96, 96};
  GridObserver a(Eigen::Vector2d::Zero(), Eigen::Matrix2d::Identity(), opt), b = a;
  const Eigen::Matrix2d Qinv = model.process_noise.inverse();
  auto log_noise = [&](const Eigen::Ref<const Eigen::VectorXd>& v) { return -0.5 * v.dot(Qinv * v); };
  for (int k = 0; k < 20; ++k) {
    a.Predict(model, sim.u[k]);
    b.Predict(model, sim.u[k], log_noise);
    a.Correct(*meas, sim.y[k]);
    b.Correct(*meas, sim.y[k]);
  }
  const double d2 = a.spacing(0) * a.spacing(1);
  EXPECT_LT((a.mean() - b.mean()).norm(), 0.05 * std::sqrt(d2));
  EXPECT_LT((a.covariance() - b.covariance()).cwiseAbs().maxCoeff(), 0.5 * d2);
}

TEST(GridObserver, RejectsBadOptionsAndImpossibleReadings) {
  GridObserverOptions opt;
  opt.points = {4, 4};
  EXPECT_THROW(GridObserver(Eigen::Vector2d::Zero(), Eigen::Matrix2d::Identity(), opt), InvalidArgument);
  opt.points = {32, 32, 32, 32};
  EXPECT_THROW(GridObserver(Eigen::Vector4d::Zero(), Eigen::Matrix4d::Identity(), opt), InvalidArgument);
  opt.points = {32};
  GridObserver g(Eigen::VectorXd::Zero(1), Eigen::MatrixXd::Identity(1, 1), opt);
  models::ThresholdSensor sensor(Eigen::VectorXd::Ones(1), 50.0);
  const Eigen::VectorXd m = g.mean();
  EXPECT_EQ(g.Correct(sensor, 1.0).status, StepStatus::kNumericalFailure);  // no grid mass beyond 50
  EXPECT_EQ(g.mean(), m);
  EXPECT_EQ(g.Correct(sensor, 0.5).status, StepStatus::kRejectedInvalid);
}

}  // namespace
}  // namespace ident
