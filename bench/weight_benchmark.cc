// ns per call of the weight β(t) alone (approx/weighting_polynomial.h): the fast SolveWeight against the
// spec §5 reference SolveWeightReference, on the weighting problems (ν, ξ, ξ_z) that the Cauchy and
// Student-t (k = 3) estimators actually meet on kh_benchmark's stream (Cauchy noise, 5 % ±50 outliers,
// forgetting 0.99, ρ ∈ {2, 4, 8, 16, 32}), recorded once before timing. The closing table gives
// fast / reference per ρ, measured in this run; the counter `iters` is the mean number of root-finder
// iterations per call.
//
//   ./build/bench/weight_benchmark --benchmark_min_time=0.2
#include <vector>

#include <benchmark/benchmark.h>
#include <Eigen/Core>

#include "approx/weighting_polynomial.h"
#include "bench/support/ratio_reporter.h"
#include "bench/support/regression_stream.h"
#include "ident/regression/student_regression.h"

namespace {

// The problems met by the estimator with dof k on kh_benchmark's stream for n parameters.
std::vector<ident::approx::WeightingProblem> RecordProblems(int n, double k) {
  const ident::bench::RegressionStream s(
      n, {.noise = ident::bench::Noise::kCauchy, .scale = 0.1, .outlier_fraction = 0.05, .outlier_size = 50});
  ident::StudentRegressionOptions o;
  o.dof = k;
  o.forgetting.factor = 0.99;
  ident::StudentRegression est(n, o);
  std::vector<ident::approx::WeightingProblem> out;
  for (int t = 0; t < s.length(); ++t) {
    const ident::StepReport r = est.Update(s.y[t], s.z.col(t));
    if (!est.in_startup() && r.updated())
      out.push_back({r.nu, est.last_step().xi, est.last_step().xi_z, n, k, o.delta});
  }
  return out;
}

template <ident::approx::WeightSolution (*Solve)(const ident::approx::WeightingProblem&)>
void Run(benchmark::State& state, double k) {
  const std::vector<ident::approx::WeightingProblem> problems = RecordProblems(static_cast<int>(state.range(0)), k);
  size_t i = 0;
  double iterations = 0;
  for (auto _ : state) {
    const ident::approx::WeightSolution w = Solve(problems[i]);
    benchmark::DoNotOptimize(w.beta);
    iterations += w.iterations;
    if (++i == problems.size()) i = 0;
  }
  state.counters["iters"] = benchmark::Counter(iterations, benchmark::Counter::kAvgIterations);
}

void BM_FastCauchy(benchmark::State& state) { Run<ident::approx::SolveWeight>(state, 1.0); }
void BM_ReferenceCauchy(benchmark::State& state) { Run<ident::approx::SolveWeightReference>(state, 1.0); }
void BM_FastStudent3(benchmark::State& state) { Run<ident::approx::SolveWeight>(state, 3.0); }
void BM_ReferenceStudent3(benchmark::State& state) { Run<ident::approx::SolveWeightReference>(state, 3.0); }

BENCHMARK(BM_FastCauchy)->RangeMultiplier(2)->Range(2, 32);
BENCHMARK(BM_ReferenceCauchy)->RangeMultiplier(2)->Range(2, 32);
BENCHMARK(BM_FastStudent3)->RangeMultiplier(2)->Range(2, 32);
BENCHMARK(BM_ReferenceStudent3)->RangeMultiplier(2)->Range(2, 32);

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  ident::bench::RatioReporter reporter(
      {{"BM_FastCauchy", "BM_ReferenceCauchy", "Weight beta(t), Cauchy: fast vs spec §5 reference"},
       {"BM_FastStudent3", "BM_ReferenceStudent3", "Weight beta(t), Student-t k = 3: fast vs spec §5 reference"}});
  benchmark::RunSpecifiedBenchmarks(&reporter);
  benchmark::Shutdown();
  return 0;
}
