// Cost of regressor cleaning (models/output_cleaner.h) per sample: ArxRegressor Next + PushOutput
// (plain) vs Next + PushCheckedOutput with every sample flagged (the cleaning path), ARX(2,2,3).
// Report: the ratio of the two in one run (cleaning should add a few ns, no allocation).
#include <benchmark/benchmark.h>

#include <cmath>

#include "models/arx.h"

namespace {

void Run(benchmark::State& state, bool cleaning) {
  const ident::models::ArxStructure arx(2, {2}, {3});
  ident::models::ArxRegressor reg(arx, {.enabled = true, .warm_up = 1});
  Eigen::VectorXd u(1), z(arx.num_parameters());
  long t = 0;
  for (auto _ : state) {
    u(0) = std::sin(0.1 * static_cast<double>(t));
    const double y = std::cos(0.07 * static_cast<double>(t++));
    if (reg.Next(u, z) && cleaning)
      benchmark::DoNotOptimize(reg.PushCheckedOutput(y, 0.9 * y, 0.1, true));
    else
      reg.PushOutput(y);
    benchmark::DoNotOptimize(z.data());
  }
  state.SetItemsProcessed(state.iterations());
}

void BM_ArxRegressorPlain(benchmark::State& state) { Run(state, false); }
void BM_ArxRegressorCleaningEverySample(benchmark::State& state) { Run(state, true); }
BENCHMARK(BM_ArxRegressorPlain);
BENCHMARK(BM_ArxRegressorCleaningEverySample);

}  // namespace

BENCHMARK_MAIN();
