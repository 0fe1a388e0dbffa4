// Time of the batch robust references (ident/regression/batch_regression.h) against least squares on the same data:
// n rows, ρ = 4, Cauchy noise with 20 % gross outliers. Run: build/bench/batch_regression_benchmark
#include <random>

#include <benchmark/benchmark.h>
#include <Eigen/Dense>

#include "common/dense_decompositions.h"
#include "ident/regression/batch_regression.h"

namespace {

struct Record {
  Eigen::MatrixXd Z;
  Eigen::VectorXd y;
};

Record MakeRecord(Eigen::Index n) {
  std::mt19937_64 rng(7);
  std::normal_distribution<double> normal;
  std::cauchy_distribution<double> cauchy(0, 0.5);
  std::uniform_real_distribution<double> unit;
  Record r{Eigen::MatrixXd(n, 4), Eigen::VectorXd(n)};
  for (Eigen::Index i = 0; i < n; ++i) {
    r.Z.row(i) << 1, normal(rng), normal(rng), normal(rng);
    r.y(i) = r.Z.row(i).dot(Eigen::Vector4d(1, -2, 0.5, 3)) + cauchy(rng) + (unit(rng) < 0.2 ? 50 : 0);
  }
  return r;
}

void BM_LeastSquares(benchmark::State& state) {
  const Record r = MakeRecord(state.range(0));
  for (auto _ : state) benchmark::DoNotOptimize(ident::dense::ColPivQr(r.Z).solve(r.y).eval());
}
void BM_Huber(benchmark::State& state) {
  const Record r = MakeRecord(state.range(0));
  for (auto _ : state) benchmark::DoNotOptimize(ident::HuberRegression(r.Z, r.y).theta);
}
void BM_CauchyMl(benchmark::State& state) {
  const Record r = MakeRecord(state.range(0));
  for (auto _ : state) benchmark::DoNotOptimize(ident::CauchyMlRegression(r.Z, r.y).theta);
}

BENCHMARK(BM_LeastSquares)->Arg(100)->Arg(500)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_Huber)->Arg(100)->Arg(500)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_CauchyMl)->Arg(100)->Arg(500)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
