// ns per update of the Kárný–Hangos Cauchy and Student-t (k = 3) estimators (ident/regression/student_regression.h)
// against the LD-form RLS (ident/regression/rls.h), all dynamic-size, exponential forgetting 0.99, on a
// pre-generated regression stream with Cauchy noise and ρ ∈ {2, 4, 8, 16, 32} parameters. The closing
// tables give cauchy / RLS and student / RLS per ρ, measured in this run. Goal: cauchy ≤ 1.3× RLS.
// BM_SafeCauchy: the Cauchy estimator with ident fit's lock-in safeguard (ident/regression/safe_student_regression.h).
// BM_CauchyWithoutRoot splits the ratio: the Cauchy step with a free weight (β = 1/ν) against RLS, and
// the full Cauchy step against it (what the root of the weighting cubic adds, docs/explanation/karny-hangos-estimator.md).
//
//   ./build/bench/kh_benchmark --benchmark_min_time=0.2
//   ./build/bench/kh_benchmark --benchmark_repetitions=5 --benchmark_enable_random_interleaving=true
//                                 (medians of five repetitions in random order: steadier on a shared machine)
#include <benchmark/benchmark.h>
#include <Eigen/Core>

#include "bench/support/ratio_reporter.h"
#include "bench/support/regression_stream.h"
#include "ident/regression/internal/extended_information.h"
#include "ident/regression/internal/step_driver.h"
#include "ident/regression/rls.h"
#include "ident/regression/safe_student_regression.h"
#include "ident/regression/student_regression.h"

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

// What `ident fit --estimator cauchy` runs: the same estimator inside SafeStudentRegression, which adds the
// lock-in monitor's O(1) bookkeeping and a ring of the recent samples to every update (restarts, if the
// monitor flags any on this stream, included). Given spec §8's default prior explicitly, so that its
// data-driven start-up is off: after BM_Cauchy's own start-up window the two differ by the safeguard only.
void BM_SafeCauchy(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const ident::bench::RegressionStream s = MakeStream(n);
  ident::SafeStudentOptions o;
  o.base.forgetting.factor = kForgetting;
  o.base.prior = o.base.DefaultPrior(n);
  ident::SafeStudentRegression est(n, o);
  Run(state, est, s);
}

// Everything a Cauchy update does except the root of the weighting cubic: the same guarded step
// (StepDriver<>::Run<true>: ξ, ξ_z and the sums the plan reuses, the plan from those sums, the guard,
// the commit) with β = 1/ν + 0·(ξ + ξ_z) — the weight kept dependent on ξ, ξ_z as the root is, but free.
// cauchy / this = what the root adds; this / RLS = what the rest of the Kárný–Hangos step adds.
void BM_CauchyWithoutRoot(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const ident::bench::RegressionStream s = MakeStream(n);
  const ident::RegressionPrior prior = ident::StudentRegressionOptions{}.DefaultPrior(n);
  ident::ExtendedInformation<> stats(prior);
  ident::StepDriver<> driver(stats);
  const ident::LdFactor<> prior_factor(prior.V0);
  const ident::StepSettings settings{kForgetting, false, ident::StudentRegression::kWindupFloor};
  const auto weight = [](double nu, const ident::Innovation& in) { return 1 / nu + 0.0 * (in.xi + in.xi_z); };
  int t = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(
        driver.Run</*WithXi=*/true>(stats, settings, prior.nu0, prior_factor, s.y[t], s.z.col(t), weight));
    t = (t + 1) % s.length();
  }
  benchmark::DoNotOptimize(stats.parameters());
}
void BM_Student3(benchmark::State& state) { BM_Student(state, 3.0); }

BENCHMARK(BM_LdRls)->RangeMultiplier(2)->Range(2, 32);
BENCHMARK(BM_Cauchy)->RangeMultiplier(2)->Range(2, 32);
BENCHMARK(BM_Student3)->RangeMultiplier(2)->Range(2, 32);
BENCHMARK(BM_SafeCauchy)->RangeMultiplier(2)->Range(2, 32);
BENCHMARK(BM_CauchyWithoutRoot)->RangeMultiplier(2)->Range(2, 32);

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  ident::bench::RatioReporter reporter(
      {{"BM_Cauchy", "BM_LdRls", "Cauchy (Kárný–Hangos) vs LD-form RLS"},
       {"BM_Student3", "BM_LdRls", "Student-t k = 3 vs LD-form RLS"},
       {"BM_SafeCauchy", "BM_Cauchy", "Cauchy with the lock-in safeguard (ident fit's default) vs without"},
       {"BM_CauchyWithoutRoot", "BM_LdRls", "Cauchy's step without the root vs LD-form RLS"},
       {"BM_Cauchy", "BM_CauchyWithoutRoot", "Cauchy vs its step without the root"}});
  benchmark::RunSpecifiedBenchmarks(&reporter);
  benchmark::Shutdown();
  return 0;
}
