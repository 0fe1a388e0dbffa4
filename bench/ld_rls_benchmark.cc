// ns per update of the LD-factorised RLS (ident/rls.h) against the dense covariance-form oracle
// (ident/dense_rls.h), both dynamic-size, forgetting 0.99, on a pre-generated random regression
// stream with n ∈ {2, 4, 8, 16, 32} parameters. The closing table gives LD / dense per n, measured
// in this run. Goal (foundation issue): LD ≤ 1.2× dense at every n.
//
//   ./build/bench/ld_rls_benchmark --benchmark_min_time=0.2
#include <random>
#include <vector>

#include <Eigen/Core>
#include <benchmark/benchmark.h>

#include "bench/support/ratio_reporter.h"
#include "ident/dense_rls.h"
#include "ident/rls.h"

namespace {

constexpr double kForgetting = 0.99;
constexpr int kStreamLength = 4096;

// A fixed stream of (y, z) with y = θ'z + e, θ and z standard normal, e ~ N(0, 0.1²).
struct Stream {
  explicit Stream(int n) : z(n, kStreamLength), y(kStreamLength) {
    std::mt19937_64 rng(20261123 + n);
    std::normal_distribution<double> g;
    Eigen::VectorXd theta(n);
    for (int i = 0; i < n; ++i) theta[i] = g(rng);
    for (int t = 0; t < kStreamLength; ++t) {
      for (int i = 0; i < n; ++i) z(i, t) = g(rng);
      y[t] = theta.dot(z.col(t)) + 0.1 * g(rng);
    }
  }
  Eigen::MatrixXd z;
  Eigen::VectorXd y;
};

void BM_LdRls(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const Stream s(n);
  ident::RecursiveLeastSquares rls(n, {.forgetting = {.factor = kForgetting}});
  int t = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(rls.Update(s.y[t], s.z.col(t)));
    t = (t + 1) % kStreamLength;
  }
  benchmark::DoNotOptimize(rls.parameters());
}

void BM_DenseRls(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const Stream s(n);
  ident::BasicDenseRls<> dense(ident::RegressionPrior::Flat(n), kForgetting);
  int t = 0;
  for (auto _ : state) {
    dense.Update(s.y[t], s.z.col(t));
    benchmark::ClobberMemory();
    t = (t + 1) % kStreamLength;
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
