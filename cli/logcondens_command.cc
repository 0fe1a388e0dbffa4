// ident logcondens SAMPLES.csv [--column NAME] [--json]
// The nonparametric log-concave MLE of a univariate sample (ident/density/logconcave_mle.h): knots, the
// log-density phi at the knots, and the log-likelihood sum_i log f_hat(X_i).
#include <algorithm>
#include <ctime>
#include <iostream>
#include <memory>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "cli/commands.h"
#include "cli/csv_options.h"
#include "cli/progress.h"
#include "common/error.h"
#include "ident/density/logconcave_mle.h"
#include "ident/io/csv.h"
#include "ident/io/mat_file.h"

namespace ident::cli {
namespace {

struct LogcondensOptions {
  std::string samples;
  std::string column;
  io::CsvOptions csv;
  bool json = false;
};

std::vector<double> ReadSamples(const LogcondensOptions& o, Progress& progress) {
  io::CsvOptions csv = o.csv;
  csv.on_read = ReadingProgress(progress, o.samples);
  const io::DataTable table = io::ReadDataFile(o.samples, csv);
  int col = 0;
  if (!o.column.empty()) {
    col = table.ColumnIndex(o.column);
  } else if (table.names.size() > 1) {
    auto it = std::find(table.names.begin(), table.names.end(), "x");
    if (it == table.names.end())
      throw InvalidArgument(
          fmt::format("{} has {} columns and none is named 'x'; pass --column NAME", o.samples, table.names.size()));
    col = static_cast<int>(it - table.names.begin());
  }
  std::vector<double> x(table.num_rows());
  for (int i = 0; i < table.num_rows(); ++i) x[i] = table.values(i, col);
  return x;
}

void RunLogcondens(const LogcondensOptions& o) {
  Progress progress("logcondens");  // on stderr after 2 s: the reading, then the active-set rounds
  const std::vector<double> samples = ReadSamples(o, progress);
  approx::LogConcaveMleOptions options;
  options.on_iteration =
      DecadesProgress(progress, options.tolerance, "decades of the largest D_j down to the tolerance");
  const std::clock_t start = std::clock();  // process CPU time of the fit alone (no CSV reading, no start-up)
  const approx::LogConcaveMle mle = approx::FitLogConcaveMle(samples, options);
  const double fit_cpu_seconds = static_cast<double>(std::clock() - start) / CLOCKS_PER_SEC;
  const approx::LogConcaveKkt kkt = approx::CheckKkt(mle);
  if (o.json) {
    nlohmann::ordered_json j;
    j["n"] = mle.n;
    j["distinct"] = mle.x.size();
    j["knots"] = std::vector<double>(mle.knots.data(), mle.knots.data() + mle.knots.size());
    j["phi"] = std::vector<double>(mle.knot_phi.data(), mle.knot_phi.data() + mle.knot_phi.size());
    j["loglik"] = mle.loglik;
    j["iterations"] = mle.iterations;
    j["kkt"] = {{"max_directional_derivative", kkt.max_directional_derivative},
                {"max_knot_residual", kkt.max_knot_residual},
                {"mass_error", kkt.mass_error}};
    j["fit_cpu_seconds"] = fit_cpu_seconds;
    std::cout << j.dump(2) << "\n";
    return;
  }
  fmt::print("{}: log-concave MLE of {} samples ({} distinct), {} knots, {} active-set changes\n", o.samples, mle.n,
             mle.x.size(), mle.knots.size(), mle.iterations);
  fmt::print("log-likelihood sum log f(X_i) = {:.10g}\n\n  {:>16} {:>16}\n", mle.loglik, "knot", "phi");
  for (int a = 0; a < mle.knots.size(); ++a) fmt::print("  {:>16.10g} {:>16.10g}\n", mle.knots(a), mle.knot_phi(a));
  fmt::print("\nKKT: max D = {:.1e}, max |D| at knots = {:.1e}, |int f - 1| = {:.1e}\n", kkt.max_directional_derivative,
             kkt.max_knot_residual, kkt.mass_error);
}

}  // namespace

void AddLogcondensCommand(CLI::App& app) {
  auto o = std::make_shared<LogcondensOptions>();
  CLI::App* cmd =
      app.add_subcommand("logcondens", "Log-concave density MLE of a univariate sample (knots, phi, loglik)");
  cmd->add_option("SAMPLES", o->samples, "CSV file with a header; one column, or a column named x, or --column")
      ->required();
  cmd->add_option("--column", o->column, "Column holding the samples");
  cmd->add_flag("--json", o->json, "Print one JSON object {knots, phi, loglik, ...}");
  AddDelimiterOption(*cmd, o->csv);
  cmd->callback([o] { RunLogcondens(*o); });
}

}  // namespace ident::cli
