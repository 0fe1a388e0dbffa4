// Log-concave density MLE (active set): time for n = 10^3 … 10^6 standard normal samples (seeded).
// The comparison with R's logcondens on the same sizes is bench/compare_logcondens.R.
#include <random>

#include <benchmark/benchmark.h>

#include "ident/density/logconcave_mle.h"

namespace {

void BM_LogConcaveMle(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  std::mt19937 rng(7);
  std::normal_distribution<double> normal(0, 1);
  std::vector<double> x(n);
  for (double& v : x) v = normal(rng);
  ident::approx::LogConcaveMle mle;
  for (auto _ : state) {
    mle = ident::approx::FitLogConcaveMle(x);
    benchmark::DoNotOptimize(mle.loglik);
  }
  state.counters["knots"] = static_cast<double>(mle.knots.size());
  state.counters["active_set_changes"] = mle.iterations;
  state.SetComplexityN(n);
}

BENCHMARK(BM_LogConcaveMle)->RangeMultiplier(10)->Range(1000, 1000000)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
