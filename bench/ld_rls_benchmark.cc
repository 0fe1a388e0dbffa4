// ns per update of the LD-factorised RLS (ident/regression/rls.h) against the dense covariance-form oracle
// (tests/support/dense_rls.h), both dynamic-size, forgetting 0.99, on a pre-generated random regression
// stream with n ∈ {2, 4, 8, 16, 32} parameters. The closing table gives LD / dense per n, measured
// in this run. Goal (foundation issue): LD ≤ 1.2× dense at every n.
//
//   ./build/bench/ld_rls_benchmark --benchmark_repetitions=5 --benchmark_enable_random_interleaving=true
//
// At n = 2 and 4 an update takes 100–170 ns, and a single pass swings the ratio between 0.7 and 1.6 on a
// shared 2-core VM; five repetitions run in random order, compared by their medians (the table uses
// medians when repetitions are given), put both sides under the same machine states.
#include <benchmark/benchmark.h>
#include <Eigen/Core>

#include "bench/support/ratio_reporter.h"
#include "bench/support/regression_stream.h"
#include "ident/regression/rls.h"
#include "tests/support/dense_rls.h"

namespace {

constexpr double kForgetting = 0.99;

// A fixed stream of (y, z) with y = θ'z + e, θ and z standard normal, e ~ N(0, 0.1²)
// (bench/support/regression_stream.h).
const ident::bench::StreamOptions kGaussian{.noise = ident::bench::Noise::kGaussian, .scale = 0.1};

void BM_LdRls(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const ident::bench::RegressionStream s(n, kGaussian);
  ident::RecursiveLeastSquares rls(n, {.forgetting = {.factor = kForgetting}});
  int t = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(rls.Update(s.y[t], s.z.col(t)));
    t = (t + 1) % s.length();
  }
  benchmark::DoNotOptimize(rls.parameters());
}

void BM_DenseRls(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const ident::bench::RegressionStream s(n, kGaussian);
  ident::BasicDenseRls<> dense(ident::RegressionPrior::Flat(n), kForgetting);
  int t = 0;
  for (auto _ : state) {
    dense.Update(s.y[t], s.z.col(t));
    benchmark::ClobberMemory();
    t = (t + 1) % s.length();
  }
  benchmark::DoNotOptimize(dense.parameters());
}

BENCHMARK(BM_LdRls)->RangeMultiplier(2)->Range(2, 32);
BENCHMARK(BM_DenseRls)->RangeMultiplier(2)->Range(2, 32);

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  ident::bench::RatioReporter reporter({{"BM_LdRls", "BM_DenseRls", "LD-form RLS vs dense covariance RLS"}});
  benchmark::RunSpecifiedBenchmarks(&reporter);
  benchmark::Shutdown();
  return 0;
}
