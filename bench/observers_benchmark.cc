// Cost per step of the log-concave observers on the MEMS accelerometer (2 states, threshold sensor):
// grid Bayesian observer (48² … 256² nodes; kernel_builds_per_step: how often its noise kernel is
// rebuilt), log-concave Gaussian filter (exact tilted moments and
// the first-passage/σ_o variant's Gaussian reading; the crossing wedge of lc_wedge at a change of the
// reading; lc_excursion's fixed-lag EP over each excursion, averaged over a run), square-root Kalman
// filter, bound tracker.
// Filters in both forms: dynamic sizes and fixed-size (BasicKalmanFilter<2>, BasicLcGaussianFilter<2>).
// Readings alternate 0 / 0 / ... / ±1 as in a run with events, precomputed before timing.
#include <random>
#include <vector>

#include <benchmark/benchmark.h>

#include "ident/observers/covariance_bound.h"
#include "ident/observers/grid_observer.h"
#include "ident/observers/kalman_filter.h"
#include "ident/observers/lc_gaussian_filter.h"
#include "ident/observers/truncated_gaussian_filter.h"
#include "models/measurement.h"
#include "models/state_space.h"
#include "studies/mems/crossing_reading.h"
#include "studies/mems/excursion_reading.h"
#include "studies/mems/window_ep_filter.h"

namespace {

struct Run {
  std::vector<Eigen::VectorXd> u;
  std::vector<double> y;
};

// A simulated ping-pong run (h = 0.01, σ² = 1) with a simple state-feedback law.
const Run& MemsRun() {
  static const Run run = [] {
    Run r;
    const auto model = ident::models::MemsAccelerometerDynamics(0.01, 1.0);
    ident::models::ThresholdSensor sensor(Eigen::Vector2d(1, 0), 1.0);
    std::mt19937_64 rng(1);
    std::normal_distribution<double> N;
    const Eigen::Matrix2d L = Eigen::LLT<Eigen::Matrix2d>(Eigen::Matrix2d(model.process_noise)).matrixL();
    Eigen::Vector2d x(0, 2);
    Eigen::VectorXd u = Eigen::VectorXd::Zero(1);
    double dir = 1;
    for (int k = 0; k < 4096; ++k) {
      x = model.A * x + model.B * u + L * Eigen::Vector2d(N(rng), N(rng));
      const double y = sensor.Measure(x);
      if (y != 0) dir = -y;
      r.u.push_back(u);
      r.y.push_back(y);
      u(0) = y != 0 ? -y * 32 : -(x(1) - dir * 4) / 0.125;
    }
    return r;
  }();
  return run;
}

void BM_GridObserver(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const auto model = ident::models::MemsAccelerometerDynamics(0.01, 1.0);
  ident::models::ThresholdSensor sensor(Eigen::Vector2d(1, 0), 1.0);
  Eigen::Matrix2d P0;
  P0 << 0.3, 0, 0, 1;
  ident::GridObserverOptions opt;
  opt.points = {n, n};
  ident::GridObserver grid(Eigen::Vector2d(0, 2), P0, opt);
  const Run& run = MemsRun();
  size_t k = 0;
  for (auto _ : state) {
    grid.Predict(model, run.u[k]);
    auto report = grid.Correct(sensor, run.y[k]);
    benchmark::DoNotOptimize(report);
    k = (k + 1) % run.y.size();
  }
  state.SetItemsProcessed(state.iterations());
  state.counters["kernel_builds_per_step"] = static_cast<double>(grid.kernel_builds()) / state.iterations();
}
BENCHMARK(BM_GridObserver)->Arg(48)->Arg(64)->Arg(96)->Arg(128)->Arg(256)->Unit(benchmark::kMicrosecond);

template <class Filter>
void BM_LcGaussianFilterExact(benchmark::State& state) {
  const auto model = ident::models::MemsAccelerometerDynamics(0.01, 1.0);
  ident::models::ThresholdSensor sensor(Eigen::Vector2d(1, 0), 1.0);
  Filter f(Eigen::Vector2d(0, 2), Eigen::Matrix2d::Identity());
  const Run& run = MemsRun();
  size_t k = 0;
  for (auto _ : state) {
    f.Predict(model, run.u[k]);
    auto report = f.Correct(sensor, run.y[k]);
    benchmark::DoNotOptimize(report);
    k = (k + 1) % run.y.size();
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK_TEMPLATE(BM_LcGaussianFilterExact, ident::LcGaussianFilter)->Unit(benchmark::kMicrosecond);
BENCHMARK_TEMPLATE(BM_LcGaussianFilterExact, ident::BasicLcGaussianFilter<2>)->Unit(benchmark::kMicrosecond);

template <class Filter>
void BM_LcGaussianFilterEventVariant(benchmark::State& state) {
  // The study's lc_gaussian column: Gaussian readings (first passage / σ_o) or exact half-line moments.
  const auto model = ident::models::MemsAccelerometerDynamics(0.01, 1.0);
  ident::models::ThresholdSensor sensor(Eigen::Vector2d(1, 0), 1.0);
  Filter f(Eigen::Vector2d(0, 2), Eigen::Matrix2d::Identity());
  const Eigen::Vector2d c(1, 0);
  const Run& run = MemsRun();
  size_t k = 0;
  double y_prev = 0;
  for (auto _ : state) {
    f.Predict(model, run.u[k]);
    const double y = run.y[k];
    ident::StepReport report;
    if (y == 0 || y_prev == 0) {
      const double s2 = f.covariance()(0, 0), m = f.mean()(0), r = y == 0 && y_prev == 0 ? 15.1 : 1e-4;
      const double target = y == 0 && y_prev == 0 ? 0.0 : (y != 0 ? y : y_prev);
      report = f.ApplyTilt(c, {0.0, m + s2 / (s2 + r) * (target - m), s2 * r / (s2 + r), true});
    } else {
      report = f.Correct(sensor, y);
    }
    benchmark::DoNotOptimize(report);
    y_prev = y;
    k = (k + 1) % run.y.size();
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK_TEMPLATE(BM_LcGaussianFilterEventVariant, ident::LcGaussianFilter)->Unit(benchmark::kMicrosecond);
BENCHMARK_TEMPLATE(BM_LcGaussianFilterEventVariant, ident::BasicLcGaussianFilter<2>)->Unit(benchmark::kMicrosecond);

// One crossing update (the exact wedge of (x1(k−1), x1(k)), studies/mems/crossing_reading.h) after a prediction,
// on a state near the threshold: the cost of a step where the reading changes (≈ 2 per event).
void BM_LcCrossingWedge(benchmark::State& state) {
  const auto model = ident::models::MemsAccelerometerDynamics(0.01, 1.0);
  const ident::models::ThresholdSensor sensor(Eigen::Vector2d(1, 0), 1.0);
  const Eigen::Vector2d m_before(0.97, 3.5);
  Eigen::Matrix2d P_before;
  P_before << 2e-3, 5e-3, 5e-3, 0.25;
  const Eigen::VectorXd u = Eigen::VectorXd::Zero(1);
  ident::BasicLcGaussianFilter<2> f(m_before, P_before);
  for (auto _ : state) {
    ident::BasicLcGaussianFilter<2> g = f;
    g.Predict(model, u);
    benchmark::DoNotOptimize(ident::CorrectReadingChange(g, m_before, P_before, model, sensor, 0.0, 1.0));
    benchmark::DoNotOptimize(g.mean());
  }
}
BENCHMARK(BM_LcCrossingWedge)->Unit(benchmark::kMicrosecond);

// The study's lc_excursion variant, averaged per step over the precomputed run (events, excursions of
// ≈ 25 steps with this run's push-back, and the σ_o reading of repeated y = 0 between them).
void BM_LcExcursionVariant(benchmark::State& state) {
  const auto model = ident::models::MemsAccelerometerDynamics(0.01, 1.0);
  const ident::models::ThresholdSensor sensor(Eigen::Vector2d(1, 0), 1.0);
  ident::LcGaussianFilter f(Eigen::Vector2d(0, 2), Eigen::Matrix2d::Identity());
  ident::ExcursionReading excursion(sensor, 2);
  const Eigen::Vector2d c(1, 0);
  Eigen::VectorXd m_before(2);
  Eigen::MatrixXd P_before(2, 2);
  const Run& run = MemsRun();
  size_t k = 0;
  double y_prev = 0;
  for (auto _ : state) {
    m_before = f.mean();
    P_before = f.covariance();
    f.Predict(model, run.u[k]);
    const double y = run.y[k];
    ident::StepReport report;
    if (y != y_prev || excursion.active()) report = excursion.Step(f, m_before, P_before, model, run.u[k], y_prev, y);
    if (!report.updated() && y == y_prev) {
      const double s2 = f.covariance()(0, 0), m = f.mean()(0), r = 15.1;
      report = f.ApplyTilt(c, {0.0, m + s2 / (s2 + r) * (y - m), s2 * r / (s2 + r), true});
    }
    benchmark::DoNotOptimize(report);
    y_prev = y;
    k = (k + 1) % run.y.size();
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_LcExcursionVariant)->Unit(benchmark::kMicrosecond);

// One filter step (Step(model, u(k−1), y(k))) per benchmark iteration, cycling through the precomputed run.
template <class Filter>
void StepThroughMemsRun(benchmark::State& state, Filter& f, const ident::models::LinearStateSpace& model) {
  const Run& run = MemsRun();
  size_t k = 0;
  for (auto _ : state) {
    auto report = f.Step(model, run.u[k], run.y[k]);
    benchmark::DoNotOptimize(report);
    k = (k + 1) % run.y.size();
  }
}

// The study's lc_window variant (studies/mems/window_ep_filter.h), averaged per step over the precomputed run:
// every reading of the last W steps an exact site, banded EP sweeps until the sites settle (1e-6).
void BM_LcWindowVariant(benchmark::State& state) {
  const auto model = ident::models::MemsAccelerometerDynamics(0.01, 1.0);
  const ident::models::ThresholdSensor sensor(Eigen::Vector2d(1, 0), 1.0);
  ident::WindowEpOptions opt;
  opt.window = static_cast<int>(state.range(0));
  ident::WindowEpFilter f(sensor, Eigen::Vector2d(0, 2), Eigen::Matrix2d::Identity(), opt);
  StepThroughMemsRun(state, f, model);
  state.counters["refits_per_step"] = static_cast<double>(f.refits()) / static_cast<double>(state.iterations());
  state.counters["failures"] = static_cast<double>(f.failures());
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_LcWindowVariant)->Arg(16)->Arg(32)->Arg(64)->Unit(benchmark::kMicrosecond);

// The study's lc_truncated variant (ident/observers/truncated_gaussian_filter.h), averaged per step over the same run:
// exact moments on the rectangle R(y(k−1)) × R(y(k)), then the projection onto Gaussians on R(y(k)).
void BM_LcTruncatedVariant(benchmark::State& state) {
  const auto model = ident::models::MemsAccelerometerDynamics(0.01, 1.0);
  const ident::models::ThresholdSensor sensor(Eigen::Vector2d(1, 0), 1.0);
  ident::TruncatedGaussianFilter f(sensor, Eigen::Vector2d(0, 2), Eigen::Matrix2d::Identity());
  StepThroughMemsRun(state, f, model);
  state.counters["failures"] = static_cast<double>(f.failures() + f.projection_failures());
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_LcTruncatedVariant)->Unit(benchmark::kMicrosecond);

template <class Filter>
void BM_KalmanFilter(benchmark::State& state) {
  const auto model = ident::models::MemsAccelerometerDynamics(0.01, 1.0);
  Filter kf(Eigen::Vector2d(0, 2), Eigen::Matrix2d::Identity());
  const Eigen::Vector2d c(1, 0);
  const Run& run = MemsRun();
  size_t k = 0;
  for (auto _ : state) {
    kf.Predict(model, run.u[k]);
    auto report = kf.Correct(c, 15.1, run.y[k]);
    benchmark::DoNotOptimize(report);
    k = (k + 1) % run.y.size();
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK_TEMPLATE(BM_KalmanFilter, ident::KalmanFilter)->Unit(benchmark::kMicrosecond);
BENCHMARK_TEMPLATE(BM_KalmanFilter, ident::BasicKalmanFilter<2>)->Unit(benchmark::kMicrosecond);

void BM_CovarianceBoundTracker(benchmark::State& state) {
  const auto model = ident::models::MemsAccelerometerDynamics(0.01, 1.0);
  ident::CovarianceBoundTracker bound(Eigen::Matrix2d::Identity());
  const Eigen::Vector2d c(1, 0);
  for (auto _ : state) {
    bound.Predict(model);
    auto report = bound.UpdateStrength(c, 1e4);
    benchmark::DoNotOptimize(report);
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_CovarianceBoundTracker)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
