// Throughput of `ident fit` on a large record against merely parsing the same file, in one run.
//
//   build/examples/write_large_record /tmp/ident_large.csv 10000000
//   IDENT_LARGE_CSV=/tmp/ident_large.csv build/bench/large_record_benchmark
//
//   BM_ParseOnly      CsvReader::Next over every row (the floor for any streaming pass)
//   BM_FitStreaming   workflow::FitCsvFile: ARX(2,2,1), RLS, split 0.5, mean detrending (count pass,
//                     mean pass over the estimation half, estimate + score pass)
// Items/s = data rows per second; the ratio table prints fit time / parse time.
// Peak memory is measured on the `ident` program: /usr/bin/time -v build/bin/ident fit ... .
#include <cstdlib>
#include <string>

#include <benchmark/benchmark.h>

#include "bench/support/ratio_reporter.h"
#include "ident/io/csv.h"
#include "ident/registry/estimator_registry.h"
#include "ident/workflow/data_source.h"
#include "ident/workflow/fit.h"
#include "models/arx.h"

namespace {

std::string LargeCsv() {
  const char* env = std::getenv("IDENT_LARGE_CSV");
  return env ? env : "/tmp/ident_large.csv";
}

void BM_ParseOnly(benchmark::State& state) {
  long rows = 0;
  for (auto _ : state) {
    ident::io::CsvReader reader(LargeCsv());
    Eigen::VectorXd row(reader.num_columns());
    while (reader.Next(row)) benchmark::DoNotOptimize(row.data());
    rows = reader.rows_read();
  }
  state.SetItemsProcessed(state.iterations() * rows);
}

void BM_FitStreaming(benchmark::State& state) {
  const std::string path = LargeCsv();
  long rows = 0;
  for (auto _ : state) {
    const ident::models::ArxStructure arx(2, {2}, {1});
    auto source = ident::workflow::MakeArxSource(ident::io::CsvReader(path).names(), "y", {"u"}, arx, path);
    auto estimator = ident::MakeRegressionEstimator(ident::EstimatorSettings{}, source->num_parameters());
    const ident::workflow::FitResult r = ident::workflow::FitCsvFile(path, {}, *source, *estimator, {});
    benchmark::DoNotOptimize(r.theta.data());
    rows = r.samples_estimation + r.samples_validation;
  }
  state.SetItemsProcessed(state.iterations() * rows);
}

BENCHMARK(BM_ParseOnly)->Arg(1)->Unit(benchmark::kSecond)->Iterations(1)->UseRealTime();
BENCHMARK(BM_FitStreaming)->Arg(1)->Unit(benchmark::kSecond)->Iterations(1)->UseRealTime();

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  ident::bench::RatioReporter reporter({{"BM_FitStreaming", "BM_ParseOnly", "ident fit (streaming) / parse only"}});
  benchmark::RunSpecifiedBenchmarks(&reporter);
}
