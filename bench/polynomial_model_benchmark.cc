// ns per sample of recursive ARMAX estimation (models/pseudo_linear_regressor.h) against recursive ARX at the
// same number of parameters ρ, RLS weights: one sample is forming the regressor, the estimator's update and
// storing the output; RPLR and RPEM also read the estimate out and hand it to the regressor (stability test
// of C included), as the fit workflow does. ARMAX(n,n,n,1) (ρ = 3n) against ARX(3n/2,3n/2,1), n ∈ {2, 4}.
// The closing table gives RPLR / RLS and RPEM / RLS per ρ, measured in this run. Goal: ≤ 2×.
//
//   ./build/bench/polynomial_model_benchmark --benchmark_repetitions=5 --benchmark_enable_random_interleaving=true
#include <cmath>
#include <random>
#include <vector>

#include <benchmark/benchmark.h>
#include <Eigen/Core>

#include "bench/support/ratio_reporter.h"
#include "ident/regression/rls.h"
#include "models/arx.h"
#include "models/pseudo_linear_regressor.h"

namespace {

constexpr int kLength = 4096;

// A stream (u, y) of A y = B u + C e with stable A and C of order n (poles and zeros at 0.5, 0.3, …).
struct Stream {
  std::vector<double> u, y;
};

Stream MakeStream(int n) {
  std::mt19937_64 rng(1);
  std::normal_distribution<double> normal;
  Stream s{std::vector<double>(kLength), std::vector<double>(kLength)};
  std::vector<double> e(kLength);
  for (int t = 0; t < kLength; ++t) {
    s.u[t] = normal(rng);
    e[t] = 0.1 * normal(rng);
    double y = e[t];
    for (int k = 1; k <= n && t >= k; ++k) y += std::pow(0.5, k) * s.y[t - k] + s.u[t - k] + 0.3 * e[t - k] / k;
    s.y[t] = y;
  }
  return s;
}

void BM_ArxRls(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0)), half = 3 * n / 2;
  const Stream s = MakeStream(n);
  ident::models::ArxRegressor regressor(ident::models::ArxStructure(half, {half}, {1}));
  ident::RecursiveLeastSquares rls(3 * n);
  Eigen::VectorXd z(3 * n), u(1);
  int t = 0;
  for (auto _ : state) {
    u(0) = s.u[t];
    if (regressor.Next(u, z)) benchmark::DoNotOptimize(rls.Update(s.y[t], z));
    regressor.PushOutput(s.y[t]);
    if (++t == kLength) {
      t = 0;
      regressor.Reset();
    }
  }
  benchmark::DoNotOptimize(rls.parameters());
}

// ARMAX(n,n,n,1), or Box-Jenkins BJ(n,n/2,n/2,n,1): ρ = 3n either way.
void PolynomialRls(benchmark::State& state, ident::models::Recursion recursion, bool box_jenkins) {
  const int n = static_cast<int>(state.range(0));
  const Stream s = MakeStream(n);
  using ident::models::PolynomialStructure;
  ident::models::PseudoLinearRegressor regressor(
      box_jenkins ? PolynomialStructure::BoxJenkins(n, n / 2, n / 2, n, 1) : PolynomialStructure::Armax(n, {n}, n, {1}),
      {}, recursion);
  ident::RecursiveLeastSquares rls(3 * n);
  Eigen::VectorXd z(3 * n), u(1);
  int t = 0;
  for (auto _ : state) {
    u(0) = s.u[t];
    if (regressor.Next(u, z)) {
      benchmark::DoNotOptimize(rls.Update(regressor.LinearisedOutput(s.y[t]), z));
      regressor.TrackEstimate(rls.parameters());
    }
    regressor.PushOutput(s.y[t]);
    if (++t == kLength) {
      t = 0;
      regressor.Reset();
    }
  }
  benchmark::DoNotOptimize(rls.parameters());
}

void BM_ArmaxRplr(benchmark::State& state) { PolynomialRls(state, ident::models::Recursion::kPseudoLinear, false); }
void BM_ArmaxRpem(benchmark::State& state) { PolynomialRls(state, ident::models::Recursion::kPredictionError, false); }
void BM_BjRpem(benchmark::State& state) { PolynomialRls(state, ident::models::Recursion::kPredictionError, true); }

BENCHMARK(BM_ArxRls)->Arg(2)->Arg(4);
BENCHMARK(BM_ArmaxRplr)->Arg(2)->Arg(4);
BENCHMARK(BM_ArmaxRpem)->Arg(2)->Arg(4);
BENCHMARK(BM_BjRpem)->Arg(2)->Arg(4);

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  ident::bench::RatioReporter reporter({{"BM_ArmaxRplr", "BM_ArxRls", "RPLR ARMAX vs RLS ARX, same rho"},
                                        {"BM_ArmaxRpem", "BM_ArxRls", "RPEM ARMAX vs RLS ARX, same rho"},
                                        {"BM_BjRpem", "BM_ArxRls", "RPEM Box-Jenkins vs RLS ARX, same rho"}});
  benchmark::RunSpecifiedBenchmarks(&reporter);
  benchmark::Shutdown();
  return 0;
}
