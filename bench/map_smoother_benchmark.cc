// MAP smoother (interior point, block-tridiagonal Newton steps): time and Newton iterations for
// T = 10^2 .. 10^6 with l1 and Huber measurement noise, n = 2 (fast path; also on one thread from T = 10^4), and
// T <= 10^4 on the general path. Linear growth in T shows as a constant time per time step (items_per_second)
// and an O(N) fit.
//   Model: x_{t+1} = [[0.99, 0.1], [0, 0.95]] x_t + w,  w ~ N(0, 0.1^2 I);  z_t = x_{t,1} + v_t,
//          v_t ~ Laplace(0, 0.5) with 5 % outliers of scale 10.  Penalties: f = quadratic (covariance
//          0.01 I, x_0: I), g = l1 or Huber(kappa = 1).
#include <random>

#include <benchmark/benchmark.h>

#include "ident/smoothing/map_smoother.h"

namespace {

ident::MapSmootherProblem MakeProblem(int T, bool huber, unsigned seed = 42) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal(0, 1);
  std::exponential_distribution<double> expo(2.0);
  std::bernoulli_distribution sign(0.5), outlier(0.05);
  Eigen::MatrixXd F(2, 2), H(1, 2);
  F << 0.99, 0.1, 0, 0.95;
  H << 1, 0;
  ident::MapSmootherProblem p;
  p.F = {F};
  p.H = {H};
  p.z.resize(1, T + 1);
  Eigen::Vector2d x(normal(rng), normal(rng));
  for (int t = 0; t <= T; ++t) {
    if (t > 0) x = F * x + 0.1 * Eigen::Vector2d(normal(rng), normal(rng));
    const double v = (sign(rng) ? 1 : -1) * expo(rng) + (outlier(rng) ? 10 * normal(rng) : 0.0);
    p.z(0, t) = x(0) + v;
  }
  using ident::models::Penalty;
  p.process = {Penalty::Quadratic(Eigen::MatrixXd::Identity(2, 2)),
               Penalty::Quadratic(0.01 * Eigen::MatrixXd::Identity(2, 2))};
  p.measurement = {huber ? Penalty::Huber(1.0) : Penalty::L1()};
  return p;
}

void BM_MapSmoother(benchmark::State& state, bool huber, bool fast_path = true, int threads = 0) {
  const int T = static_cast<int>(state.range(0));
  const ident::MapSmootherProblem p = MakeProblem(T, huber);
  ident::MapSmootherOptions options;
  options.fast_path = fast_path;  // false: the general path (per-term PLQ dispatch, block Cholesky)
  options.threads = threads;      // 0: the fast path's halves on two threads from T = 1023 on; 1: one thread
  ident::MapSmootherResult r;
  for (auto _ : state) {
    r = ident::SolveMapSmoother(p, options);
    benchmark::DoNotOptimize(r.primal);
  }
  if (r.status != ident::MapSmootherStatus::kConverged) state.SkipWithError(r.message.c_str());
  state.counters["newton_iterations"] = r.iterations;
  state.counters["relative_gap"] = r.relative_gap;
  state.counters["ns_per_step_per_iteration"] =
      benchmark::Counter(static_cast<double>(T + 1) * r.iterations,
                         benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
  state.SetItemsProcessed(state.iterations() * (T + 1));
  state.SetComplexityN(T);
}

BENCHMARK_CAPTURE(BM_MapSmoother, L1, false)
    ->RangeMultiplier(10)
    ->Range(100, 1000000)
    ->Unit(benchmark::kMillisecond)
    ->Complexity(benchmark::oN);
BENCHMARK_CAPTURE(BM_MapSmoother, Huber, true)
    ->RangeMultiplier(10)
    ->Range(100, 1000000)
    ->Unit(benchmark::kMillisecond)
    ->Complexity(benchmark::oN);
// The fast path on one thread, for the second thread's speed-up measured in one run.
BENCHMARK_CAPTURE(BM_MapSmoother, L1OneThread, false, true, 1)
    ->RangeMultiplier(10)
    ->Range(10000, 1000000)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_MapSmoother, HuberOneThread, true, true, 1)
    ->RangeMultiplier(10)
    ->Range(10000, 1000000)
    ->Unit(benchmark::kMillisecond);
// The same problems on the general path, for the fast path's speed-up measured in one run.
BENCHMARK_CAPTURE(BM_MapSmoother, L1General, false, false)
    ->RangeMultiplier(10)
    ->Range(100, 10000)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_MapSmoother, HuberGeneral, true, false)
    ->RangeMultiplier(10)
    ->Range(100, 10000)
    ->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
