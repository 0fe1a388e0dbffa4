// ns per update of the log-concave Gaussian filter run as a regression estimator (ident/observers/lc_regression.h:
// lc:laplace, lc:huber, lc:logistic, lc:gengauss:1.5) against the Kárný–Hangos Cauchy estimator
// (ident/regression/student_regression.h) and the LD-form RLS, all dynamic-size, exponential forgetting 0.99,
// on a pre-generated regression stream with Cauchy noise, 5 % outliers and ρ ∈ {2, 4, 8, 16} parameters, after an
// untimed first pass (the steady state). The closing tables give lc / cauchy per ρ, measured in this run (goal:
// within 3×).
//
//   ./build/bench/lc_regression_benchmark --benchmark_repetitions=5 --benchmark_enable_random_interleaving=true
#include <string>

#include <benchmark/benchmark.h>
#include <Eigen/Core>

#include "bench/support/ratio_reporter.h"
#include "bench/support/regression_stream.h"
#include "ident/observers/lc_regression.h"
#include "ident/regression/rls.h"
#include "ident/regression/student_regression.h"

namespace {

constexpr double kLcForgetting = 0.99;

ident::bench::RegressionStream MakeLcStream(int n) {
  return ident::bench::RegressionStream(
      n, {.noise = ident::bench::Noise::kCauchy, .scale = 0.1, .outlier_fraction = 0.05, .outlier_size = 50});
}

// The steady-state cost: one untimed pass over the stream first, so that no estimator's start-up (the lc
// filter's batch start window, the Kárný–Hangos lock-in) is counted in the per-update time.
template <class E>
void RunStream(benchmark::State& state, E& est, const ident::bench::RegressionStream& s) {
  for (int t = 0; t < s.length(); ++t) benchmark::DoNotOptimize(est.Update(s.y[t], s.z.col(t)));
  int t = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(est.Update(s.y[t], s.z.col(t)));
    t = (t + 1) % s.length();
  }
  benchmark::DoNotOptimize(est.parameters());
}

void BM_Rls(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const ident::bench::RegressionStream s = MakeLcStream(n);
  ident::RecursiveLeastSquares rls(n, {.forgetting = {.factor = kLcForgetting}});
  RunStream(state, rls, s);
}

void BM_Cauchy(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const ident::bench::RegressionStream s = MakeLcStream(n);
  ident::StudentRegressionOptions o;
  o.dof = 1;
  o.forgetting.factor = kLcForgetting;
  ident::StudentRegression est(n, o);
  RunStream(state, est, s);
}

void BM_Lc(benchmark::State& state, const std::string& noise) {
  const int n = static_cast<int>(state.range(0));
  const ident::bench::RegressionStream s = MakeLcStream(n);
  ident::LcRegressionOptions o;
  o.noise = ident::models::LogConcaveNoise::Parse(noise);
  o.forgetting = kLcForgetting;
  ident::LcRegression est(n, o);
  RunStream(state, est, s);
}
void BM_LcGaussian(benchmark::State& state) { BM_Lc(state, "gaussian"); }
void BM_LcLaplace(benchmark::State& state) { BM_Lc(state, "laplace"); }
void BM_LcHuber(benchmark::State& state) { BM_Lc(state, "huber"); }
void BM_LcLogistic(benchmark::State& state) { BM_Lc(state, "logistic"); }
void BM_LcGengauss(benchmark::State& state) { BM_Lc(state, "gengauss:1.5"); }

BENCHMARK(BM_Rls)->RangeMultiplier(2)->Range(2, 16);
BENCHMARK(BM_Cauchy)->RangeMultiplier(2)->Range(2, 16);
BENCHMARK(BM_LcGaussian)->RangeMultiplier(2)->Range(2, 16);
BENCHMARK(BM_LcLaplace)->RangeMultiplier(2)->Range(2, 16);
BENCHMARK(BM_LcHuber)->RangeMultiplier(2)->Range(2, 16);
BENCHMARK(BM_LcLogistic)->RangeMultiplier(2)->Range(2, 16);
BENCHMARK(BM_LcGengauss)->RangeMultiplier(2)->Range(2, 16);

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  ident::bench::RatioReporter reporter({{"BM_LcGaussian", "BM_Cauchy", "lc:gaussian (the filter alone) vs Cauchy"},
                                        {"BM_LcLaplace", "BM_Cauchy", "lc:laplace vs Cauchy (Kárný–Hangos)"},
                                        {"BM_LcHuber", "BM_Cauchy", "lc:huber vs Cauchy"},
                                        {"BM_LcLogistic", "BM_Cauchy", "lc:logistic vs Cauchy"},
                                        {"BM_LcGengauss", "BM_Cauchy", "lc:gengauss:1.5 vs Cauchy"},
                                        {"BM_Cauchy", "BM_Rls", "Cauchy vs LD-form RLS"}});
  benchmark::RunSpecifiedBenchmarks(&reporter);
  benchmark::Shutdown();
  return 0;
}
