// A Google Benchmark console reporter that, after the usual table, prints the ratio of two families
// measured in the same run — "ours vs baseline" at every argument — since absolute times on shared
// machines are noisy but ratios measured side by side are not.
//
//   int main(int argc, char** argv) {
//     benchmark::Initialize(&argc, argv);
//     ident::bench::RatioReporter reporter({{"BM_LdRls", "BM_DenseRls", "LD / dense"}});
//     benchmark::RunSpecifiedBenchmarks(&reporter);
//   }
//
// Benchmarks are matched by name "<family>/<arg>"; the ratio uses CPU time per iteration (on a loaded
// machine wall time includes waiting for a core; CPU time does not). With --benchmark_repetitions=N the
// table uses the median of the N repetitions (robust to a neighbour's burst on a shared machine).
#pragma once

#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

namespace ident::bench {

struct RatioSpec {
  std::string numerator;    // benchmark family, e.g. "BM_Cauchy"
  std::string denominator;  // e.g. "BM_LdRls"
  std::string label;        // printed heading
};

class RatioReporter : public benchmark::ConsoleReporter {
 public:
  explicit RatioReporter(std::vector<RatioSpec> specs) : specs_(std::move(specs)) {}

  void ReportRuns(const std::vector<Run>& runs) override {
    for (const Run& run : runs) {
      if (run.error_occurred) continue;
      // With --benchmark_repetitions=N the median over the repetitions is used, else the single run.
      const bool median = run.run_type == Run::RT_Aggregate && run.aggregate_name == "median";
      if (run.run_type != Run::RT_Iteration && !median) continue;
      std::string name = run.run_name.function_name;
      if (!run.run_name.args.empty()) name += "/" + run.run_name.args;
      const auto slash = name.find('/');
      if (slash == std::string::npos) continue;
      auto& slot = times_[name.substr(0, slash)][name.substr(slash + 1)];
      if (median || run.repetitions <= 1) slot = run.GetAdjustedCPUTime();
    }
    ConsoleReporter::ReportRuns(runs);
  }

  void Finalize() override {
    ConsoleReporter::Finalize();
    for (const RatioSpec& spec : specs_) {
      const auto& num = times_[spec.numerator];
      const auto& den = times_[spec.denominator];
      std::printf("\n%s (%s / %s, same run)\n%-8s %12s %12s %8s\n", spec.label.c_str(), spec.numerator.c_str(),
                  spec.denominator.c_str(), "arg", "num [ns]", "den [ns]", "ratio");
      for (const auto& [arg, t] : num) {
        const auto it = den.find(arg);
        if (it == den.end()) continue;
        std::printf("%-8s %12.1f %12.1f %8.3f\n", arg.c_str(), t, it->second, t / it->second);
      }
    }
    std::fflush(stdout);
  }

 private:
  std::vector<RatioSpec> specs_;
  // family -> argument -> time; arguments compare numerically when both are numbers.
  struct ArgLess {
    bool operator()(const std::string& a, const std::string& b) const {
      if (a.size() != b.size()) return a.size() < b.size();
      return a < b;
    }
  };
  std::map<std::string, std::map<std::string, double, ArgLess>> times_;
};

}  // namespace ident::bench
