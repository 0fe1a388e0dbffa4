// The grid observer's step against independent computations, and the refinement check
// (ident/observers/grid_observer.h, grid_refinement.h):
//   - the noise convolution against a brute-force O(N⁴) sum with the documented kernel (lattice heat kernel
//     e^{−t} I_k(t) by Bessel functions, times the 3-node conditional offset), to 1e-12;
//   - a node-onto-node shift as an exact translation, and the double integrator's shear of a Gaussian
//     against the exact image N(A m, A P A') node by node;
//   - on MEMS runs (seeds 1, 7, 21 of the study, 300 steps): the grid RefineGrid accepts at tolerance 2 %
//     agrees with a grid twice as fine within the tolerance (the stated bound: about 0.8 · tolerance).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>

#include <gtest/gtest.h>
#include <Eigen/Cholesky>
#include <Eigen/LU>

#include "common/error.h"

#include "ident/observers/grid_observer.h"
#include "ident/observers/grid_refinement.h"
#include "models/measurement.h"
#include "models/state_space.h"
#include "tests/support/sanitizer.h"

namespace ident {
namespace {

// Lattice heat kernel with variance t (cells²): e^{−t} I_|k|(t).
double HeatKernel(int k, double t) {
  if (t == 0) return k == 0 ? 1.0 : 0.0;
  return std::exp(-t) * std::cyl_bessel_i(static_cast<double>(std::abs(k)), t);
}

// The documented 2-D kernel weight at offset (k0, k1) cells for noise covariance Q and spacings d.
double KernelWeight(int k0, int k1, const Eigen::Matrix2d& Q, const std::array<double, 2>& d) {
  const double beta = Q(1, 1) > 0 ? Q(0, 1) / Q(1, 1) : 0;
  const double v = (Q(0, 0) - beta * Q(0, 1)) / (d[0] * d[0]);
  const double r = beta * k1 * d[1] / d[0], s = std::round(r), mu = r - s;
  const int j = k0 - static_cast<int>(s);
  const double w = j == 0    ? 1 - v - mu * mu
                   : j == 1  ? 0.5 * (v + mu * mu + mu)
                   : j == -1 ? 0.5 * (v + mu * mu - mu)
                             : 0;
  return HeatKernel(k1, Q(1, 1) / (d[1] * d[1])) * w;
}

// A grid that keeps its spacing and origin through a Predict with A = I, B u = 0: the prior's 1e-12 support
// (±7.4 sd) plus noise_sigmas · noise sd within the initial ±8 sd box.
GridObserver StillGrid(int points, const Eigen::Matrix2d& P0) {
  GridObserverOptions o;
  o.points = {points, points};
  o.noise_sigmas = 0.5;
  return GridObserver(Eigen::Vector2d(0.1, -0.2), P0, o);
}

TEST(GridObserverStep, NoiseConvolutionMatchesBruteForceSumWithTheDocumentedKernel) {
  const Eigen::Matrix2d P0 = Eigen::Vector2d(1.0, 0.5).asDiagonal();
  for (const double rho : {0.0, 0.8}) {
    GridObserver grid = StillGrid(24, P0);
    const std::vector<double> before = grid.density();
    const std::array<double, 2> d{grid.spacing(0), grid.spacing(1)};
    const double o0 = grid.origin(0), o1 = grid.origin(1);
    // Noise of a few cells along axis 1, well under a cell along axis 0, correlated.
    Eigen::Matrix2d Q;
    const double q0 = 0.01 * d[0] * d[0], q1 = 2.0 * d[1] * d[1];
    Q << q0, rho * std::sqrt(q0 * q1), rho * std::sqrt(q0 * q1), q1;
    const auto model = models::LinearStateSpace::Make(Eigen::Matrix2d::Identity(), Eigen::MatrixXd::Zero(2, 1), Q);
    ASSERT_TRUE(grid.Predict(model, Eigen::VectorXd::Zero(1)).updated());
    ASSERT_EQ(grid.origin(0), o0);
    ASSERT_EQ(grid.origin(1), o1);
    ASSERT_EQ(grid.spacing(0), d[0]);
    // Brute force: every output node against every input node.
    const int n = 24;
    std::vector<double> expected(n * n, 0.0);
    double mass = 0;
    for (int i1 = 0; i1 < n; ++i1)
      for (int i0 = 0; i0 < n; ++i0) {
        double v = 0;
        for (int j1 = 0; j1 < n; ++j1)
          for (int j0 = 0; j0 < n; ++j0) v += KernelWeight(i0 - j0, i1 - j1, Q, d) * before[j0 + n * j1];
        expected[i0 + n * i1] = std::max(0.0, v);
        mass += expected[i0 + n * i1];
      }
    double worst = 0, peak = 0;
    for (int k = 0; k < n * n; ++k) {
      const double e = expected[k] / (mass * d[0] * d[1]);
      worst = std::max(worst, std::abs(grid.density()[k] - e));
      peak = std::max(peak, e);
    }
    EXPECT_LT(worst, 1e-12 * peak) << "rho = " << rho;
  }
}

TEST(GridObserverStep, WholeCellShiftIsAnExactTranslation) {
  const Eigen::Matrix2d P0 = Eigen::Vector2d(1.0, 0.5).asDiagonal();
  GridObserver grid = StillGrid(32, P0);
  const std::vector<double> before = grid.density();
  const double o0 = grid.origin(0), o1 = grid.origin(1), d0 = grid.spacing(0), d1 = grid.spacing(1);
  // x ↦ x + (3 Δ0, −2 Δ1), no noise: the grid follows by whole cells and the values move node onto node.
  Eigen::MatrixXd Bu(2, 1);
  Bu << 3 * d0, -2 * d1;
  const auto model = models::LinearStateSpace::Make(Eigen::Matrix2d::Identity(), Bu, Eigen::Matrix2d::Zero());
  ASSERT_TRUE(grid.Predict(model, Eigen::VectorXd::Ones(1)).updated());
  ASSERT_NEAR(grid.spacing(0), d0, 0);
  const int s0 = static_cast<int>(std::lround((grid.origin(0) - o0) / d0)) - 3;
  const int s1 = static_cast<int>(std::lround((grid.origin(1) - o1) / d1)) + 2;
  EXPECT_NEAR(grid.origin(0), o0 + (s0 + 3) * d0, 1e-12);
  double worst = 0, peak = 0;
  for (int j1 = 0; j1 < 32; ++j1)
    for (int j0 = 0; j0 < 32; ++j0) {
      const int k0 = j0 + s0, k1 = j1 + s1;  // old node under new node (j0, j1)
      const double old = k0 >= 0 && k0 < 32 && k1 >= 0 && k1 < 32 ? before[k0 + 32 * k1] : 0.0;
      worst = std::max(worst, std::abs(grid.density()[j0 + 32 * j1] - old));
      peak = std::max(peak, old);
    }
  EXPECT_LT(worst, 1e-12 * peak);
}

TEST(GridObserverStep, ShearOfAGaussianMatchesTheExactImage) {
  // The double integrator without noise maps N(m, P) to N(A m + B u, A P A'); cubic interpolation is
  // exact to O(Δ⁴) per step. After 20 steps, the largest node error relative to the peak.
  auto model = models::MemsAccelerometerDynamics(0.05, 1.0);
  model.process_noise.setZero();
  Eigen::Matrix2d P;
  P << 0.2, 0.05, 0.05, 0.3;
  Eigen::Vector2d m(0.3, 1.0);
  GridObserverOptions o;
  o.points = {96, 96};
  GridObserver grid(m, P, o);
  const Eigen::VectorXd u = Eigen::VectorXd::Constant(1, 0.7);
  for (int k = 0; k < 20; ++k) {
    ASSERT_TRUE(grid.Predict(model, u).updated());
    m = model.A * m + model.B * u;
    P = model.A * P * model.A.transpose();
  }
  const Eigen::Matrix2d Pinv = P.inverse();
  const double norm = 1 / (2 * std::numbers::pi * std::sqrt(P.determinant()));
  double worst = 0;
  for (int j1 = 0; j1 < 96; ++j1)
    for (int j0 = 0; j0 < 96; ++j0) {
      const Eigen::Vector2d x(grid.axis(0, j0), grid.axis(1, j1));
      const double exact = norm * std::exp(-0.5 * (x - m).dot(Pinv * (x - m)));
      worst = std::max(worst, std::abs(grid.density()[j0 + 96 * j1] - exact));
    }
  EXPECT_LT(worst, 0.04 * norm);  // measured 0.028: the cubic's dispersion moves values, not moments
  EXPECT_LT((grid.mean() - m).norm(), 1e-6);
  EXPECT_LT((grid.covariance() - P).cwiseAbs().maxCoeff(), 1e-4 * P.maxCoeff());
}

// A MEMS run as in studies/mems: ping-pong between the thresholds, true-state feedback.
struct MemsRun {
  std::vector<Eigen::VectorXd> u;
  std::vector<double> y;
};
MemsRun SimulateMems(int steps, double t_mean, unsigned seed) {
  const auto model = models::MemsAccelerometerDynamics(0.01, 1.0);
  const models::ThresholdSensor sensor(Eigen::Vector2d(1, 0), 1.0);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal;
  const Eigen::Matrix2d L = Eigen::LLT<Eigen::Matrix2d>(Eigen::Matrix2d(model.process_noise)).matrixL();
  const double v_ref = 2 / t_mean, tau = t_mean / 8;
  Eigen::Vector2d x(0, v_ref);
  Eigen::VectorXd u = Eigen::VectorXd::Zero(1);
  double direction = 1;
  MemsRun r;
  for (int k = 0; k < steps; ++k) {
    r.u.push_back(u);
    x = model.A * x + model.B * u + L * Eigen::Vector2d(normal(rng), normal(rng));
    const double y = sensor.Measure(x);
    if (y != 0) direction = -y;
    r.y.push_back(y);
    u(0) = y != 0 ? -y * 2 * v_ref / tau : -(x(1) - direction * v_ref) / tau;
  }
  return r;
}

TEST(GridRefinement, AcceptedGridAgreesWithAMuchFinerGridOnMemsRuns) {
  const auto model = models::MemsAccelerometerDynamics(0.01, 1.0);
  const models::ThresholdSensor sensor(Eigen::Vector2d(1, 0), 1.0);
  const Eigen::Vector2d m0(0, 2);
  const Eigen::Matrix2d P0 = Eigen::Vector2d(0.3, 1.0).asDiagonal();
  const int steps = testing::FullOrUnderSanitizer(300, 120);
  for (const unsigned seed : {1u, 7u, 21u}) {
    if (testing::kUnderSanitizer && seed != 7u) continue;
    const MemsRun run = SimulateMems(steps, 1.0, seed);
    auto grid_run = [&](int points) { return RunGridObserver(model, sensor, m0, P0, run.u, run.y, {points, points}); };
    GridRefinementOptions o;
    o.points = 32;
    o.tolerance = 0.02;
    o.first_step = steps / 10;
    const GridRefinementResult r = RefineGrid(grid_run, o);
    EXPECT_TRUE(r.converged) << "seed " << seed << " difference " << r.difference;
    EXPECT_EQ(r.trace.failed_steps, 0);
    const int finer = std::min(256, 2 * r.points);
    const GridTrace fine = grid_run(finer);
    const double difference = GridTraceDifference(r.trace, fine, o.first_step);
    EXPECT_LT(difference, o.tolerance) << "seed " << seed << ": " << r.points << "^2 against " << finer << "^2";
    std::printf("seed %u: %d^2 (difference %.4f to %d^2), %.4f to %d^2\n", seed, r.points, r.difference,
                r.coarse_points, difference, finer);
  }
}

TEST(GridRefinement, RejectsBadOptions) {
  auto run = [](int) { return GridTrace{}; };
  GridRefinementOptions o;
  o.points = 4;
  EXPECT_THROW(RefineGrid(run, o), InvalidArgument);
  o.points = 64;
  o.tolerance = 0;
  EXPECT_THROW(RefineGrid(run, o), InvalidArgument);
  o.tolerance = 0.01;
  o.max_points = 80;
  EXPECT_THROW(RefineGrid(run, o), InvalidArgument);
}

}  // namespace
}  // namespace ident
