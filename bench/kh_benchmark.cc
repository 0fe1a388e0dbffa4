// ns per update of the Kárný–Hangos Cauchy and Student-t (k = 3) estimators (ident/student_regression.h)
// against the LD-form RLS (ident/rls.h), all dynamic-size, exponential forgetting 0.99, on a
// pre-generated regression stream with Cauchy noise and ρ ∈ {2, 4, 8, 16, 32} parameters. The closing
// tables give cauchy / RLS and student / RLS per ρ, measured in this run. Goal (issue 3): cauchy ≤ 1.3× RLS.
//
//   ./build/bench/kh_benchmark --benchmark_min_time=0.2
#include <Eigen/Core>
#include <benchmark/benchmark.h>

#include "bench/support/ratio_reporter.h"
#include "bench/support/regression_stream.h"
#include "ident/rls.h"
#include "ident/student_regression.h"

namespace {

constexpr double kForgetting = 0.99;

// y = θ'z + 0.1·Cauchy, θ and z standard normal; 5 % of the samples get an extra ±50 outlier.
ident::bench::RegressionStream MakeStream(int n) {
  return ident::bench::RegressionStream(
      n, {.noise = ident::bench::Noise::kCauchy, .scale = 0.1, .outlier_fraction = 0.05, .outlier_size = 50});
}

template <class E>
void Run(benchmark::State& state, E& est, const ident::bench::RegressionStream& s) {
  int t = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(est.Update(s.y[t], s.z.col(t)));
    t = (t + 1) % s.length();
  }
  benchmark::DoNotOptimize(est.parameters());
}

void BM_LdRls(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const ident::bench::RegressionStream s = MakeStream(n);
  ident::RecursiveLeastSquares rls(n, {.forgetting = {.factor = kForgetting}});
  Run(state, rls, s);
}

void BM_Student(benchmark::State& state, double k) {
  const int n = static_cast<int>(state.range(0));
  const ident::bench::RegressionStream s = MakeStream(n);
  ident::StudentRegressionOptions o;
  o.dof = k;
  o.forgetting.factor = kForgetting;
  ident::StudentRegression est(n, o);
  Run(state, est, s);
}
void BM_Cauchy(benchmark::State& state) { BM_Student(state, 1.0); }
void BM_Student3(benchmark::State& state) { BM_Student(state, 3.0); }

BENCHMARK(BM_LdRls)->RangeMultiplier(2)->Range(2, 32);
BENCHMARK(BM_Cauchy)->RangeMultiplier(2)->Range(2, 32);
BENCHMARK(BM_Student3)->RangeMultiplier(2)->Range(2, 32);

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  ident::bench::RatioReporter reporter({{"BM_Cauchy", "BM_LdRls", "Cauchy (Kárný–Hangos) vs LD-form RLS"},
                                        {"BM_Student3", "BM_LdRls", "Student-t k = 3 vs LD-form RLS"}});
  benchmark::RunSpecifiedBenchmarks(&reporter);
  benchmark::Shutdown();
  return 0;
}
