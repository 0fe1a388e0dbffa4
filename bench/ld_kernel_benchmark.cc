// ns per update of ident's fixed-size RLS (ident::BasicRecursiveLeastSquares<ρ>, ident/regression/rls.h) against
// the floor of an LD update, a minimal fixed-size Agee–Turner RLS with no guard (bench/support/ld_kernel.h,
// checked by tests/regression/ld_kernel_test.cc), and of the fixed-size Kárný–Hangos Cauchy estimator
// (ident::BasicStudentRegression<ρ>, dof 1, spec §8's default prior given explicitly: no data-driven start-up)
// against that RLS. Exponential forgetting 0.99, ρ ∈ {2, 4, 8, 16, 32} as template arguments, all on the
// same pre-generated stream with Cauchy noise and 5 % outliers (bench/support/regression_stream.h) copied
// into a ρ x T matrix of fixed row count. The closing tables give RLS / kernel and Cauchy / RLS per ρ,
// measured in this run. Goals: RLS ≤ 2× kernel, Cauchy ≤ 1.3× RLS.
//
//   ./build/bench/ld_kernel_benchmark
//   ./build/bench/ld_kernel_benchmark --benchmark_repetitions=5 --benchmark_enable_random_interleaving=true
#include <array>
#include <string>

#include <benchmark/benchmark.h>
#include <Eigen/Core>

#include "bench/support/ld_kernel.h"
#include "bench/support/ratio_reporter.h"
#include "bench/support/regression_stream.h"
#include "ident/regression/rls.h"
#include "ident/regression/student_regression.h"

namespace {

constexpr double kForgetting = 0.99;

template <int Rho>
struct FixedStream {
  FixedStream() {
    const ident::bench::RegressionStream s(
        Rho, {.noise = ident::bench::Noise::kCauchy, .scale = 0.1, .outlier_fraction = 0.05, .outlier_size = 50});
    z = s.z;
    y = s.y;
  }
  int length() const { return static_cast<int>(y.size()); }
  Eigen::Matrix<double, Rho, Eigen::Dynamic> z;
  Eigen::VectorXd y;
};

template <int Rho>
void BM_LdKernel(benchmark::State& state) {
  const FixedStream<Rho> s;
  // RLS's default flat prior (ident::RegressionPrior::Flat): information ν0·V0 = 1e-12·I.
  std::array<double, Rho + 1> d0;
  d0.fill(1e-12);
  ident::bench::LdKernel<Rho> kernel(kForgetting, d0);
  int t = 0;
  for (auto _ : state) {
    kernel.Update(s.y[t], s.z.col(t).data());
    benchmark::ClobberMemory();
    t = (t + 1) % s.length();
  }
  benchmark::DoNotOptimize(kernel.Parameters());
}

template <class E, int Rho>
void Run(benchmark::State& state, E& est, const FixedStream<Rho>& s) {
  int t = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(est.Update(s.y[t], s.z.col(t)));
    t = (t + 1) % s.length();
  }
  benchmark::DoNotOptimize(est.parameters());
}

template <int Rho>
void BM_Rls(benchmark::State& state) {
  const FixedStream<Rho> s;
  ident::BasicRecursiveLeastSquares<Rho> rls(Rho, {.forgetting = {.factor = kForgetting}});
  Run(state, rls, s);
}

template <int Rho>
void BM_Cauchy(benchmark::State& state) {
  const FixedStream<Rho> s;
  ident::StudentRegressionOptions o;
  o.dof = 1;
  o.forgetting.factor = kForgetting;
  o.prior = o.DefaultPrior(Rho);
  ident::BasicStudentRegression<Rho> est(Rho, o);
  Run(state, est, s);
}

// Registered as "<family>/<ρ>", the names the ratio tables and bench/run-baselines match.
template <int Rho>
void Register() {
  const std::string arg = "/" + std::to_string(Rho);
  benchmark::RegisterBenchmark(("BM_LdKernel" + arg).c_str(), BM_LdKernel<Rho>);
  benchmark::RegisterBenchmark(("BM_Rls" + arg).c_str(), BM_Rls<Rho>);
  benchmark::RegisterBenchmark(("BM_Cauchy" + arg).c_str(), BM_Cauchy<Rho>);
}

}  // namespace

int main(int argc, char** argv) {
  Register<2>();
  Register<4>();
  Register<8>();
  Register<16>();
  Register<32>();
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  ident::bench::RatioReporter reporter({{"BM_Rls", "BM_LdKernel", "fixed-size RLS vs the minimal LD kernel"},
                                        {"BM_Cauchy", "BM_Rls", "fixed-size Cauchy (Kárný–Hangos) vs fixed-size RLS"}});
  benchmark::RunSpecifiedBenchmarks(&reporter);
  benchmark::Shutdown();
  return 0;
}
