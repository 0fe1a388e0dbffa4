// ident stream [DATA] [--experiment-column NAME] --output y (--input u [--na --nb --nk] | --regressors x1,x2 [--intercept])
//              [--estimator NAME ...] [--missing] [--flush-every N]
// Reads CSV rows as they arrive (standard input, a pipe, a FIFO or a file) and prints one JSON line per
// row: {"t": row, "theta": [...], "weight": β, "nu": ν, "status": "..."} (ident/workflow/stream.h).
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <iterator>
#include <memory>
#include <optional>
#include <system_error>

#include <fmt/format.h>

#include "cli/commands.h"
#include "cli/csv_options.h"
#include "cli/estimator_options.h"
#include "cli/experiment_records.h"
#include "cli/structure_options.h"
#include "common/error.h"
#include "ident/io/arriving_input.h"
#include "ident/io/csv.h"
#include "ident/registry/estimator_registry.h"
#include "ident/workflow/stream.h"
#include "ident/workflow/time_column.h"

namespace ident::cli {
namespace {

struct StreamCommandOptions {
  std::string data = io::kStandardInput;
  std::string experiment_column;
  StructureCliOptions structure;
  EstimatorCliOptions estimator;
  bool missing = false;
  io::CsvOptions csv;  // --delimiter
  long flush_every = 1;
};

// A JSON number: the shortest decimal that reads back bit for bit; null for NaN and ±Inf.
void AppendNumber(fmt::memory_buffer& line, double v) {
  if (std::isfinite(v))
    fmt::format_to(std::back_inserter(line), "{}", v);
  else
    line.append(std::string_view("null"));
}

void WriteLine(fmt::memory_buffer& line, const workflow::StreamStep& step, const Eigen::VectorXd& theta) {
  line.clear();
  fmt::format_to(std::back_inserter(line), "{{\"t\": {}, \"theta\": [", step.row);
  for (Eigen::Index i = 0; i < theta.size(); ++i) {
    if (i) line.append(std::string_view(", "));
    AppendNumber(line, theta(i));
  }
  line.append(std::string_view("], \"weight\": "));
  AppendNumber(line, step.weight);
  line.append(std::string_view(", \"nu\": "));
  AppendNumber(line, step.nu);
  fmt::format_to(std::back_inserter(line), ", \"status\": \"{}\"}}\n", workflow::ToString(step.status));
  std::fwrite(line.data(), 1, line.size(), stdout);
}

// A write to standard output failed (a full disk, a closed descriptor): main reports it.
void CheckStandardOutput() {
  if (std::ferror(stdout)) throw std::system_error(errno ? errno : EIO, std::generic_category(), "standard output");
}

void RunStream(const StreamCommandOptions& o) {
  IDENT_REQUIRE(o.flush_every >= 0, "--flush-every {}; need 0 (only before waiting for input) or more lines",
                o.flush_every);
  const OutlierDecision decision = o.structure.Decision();  // bad options fail before any input is read
  (void)RegressionEstimatorTraits(ParseEstimatorSpec(o.estimator.estimator).name);
  const std::string path = o.data == io::kStandardInput ? o.data : ResolveDataPath(o.data);
  // Every line of the rows read so far is out before the program waits for more input.
  io::CsvReader reader(io::OpenArrivingInput(path, [] { std::fflush(stdout); }),
                       path == io::kStandardInput ? "standard input" : path,
                       {.missing_as_nan = o.missing, .delimiter = o.csv.delimiter});
  const std::unique_ptr<workflow::DataSource> source = o.structure.MakeSource(reader.names(), reader.path());
  const EstimatorSettings settings = o.estimator.Resolve(source->num_parameters());
  const std::unique_ptr<AnyRegressionEstimator> estimator = MakeRegressionEstimator(settings, source->num_parameters());
  workflow::StreamEstimation stream(*source, *estimator, decision);
  // Each change of the experiment column's label starts a further experiment: the regressors restart.
  const int label_column = o.experiment_column.empty() ? -1 : reader.ColumnIndex(o.experiment_column);
  double label = 0;
  // The time column of a single experiment (a time column restarts in each), checked as rows arrive
  // (workflow::ArrivingTimeCheck); --missing fills a gap with its missing rows, as ident fit does.
  const int time_column = label_column < 0 ? workflow::TimeColumnIndex(reader.names(), source->used_columns()) : -1;
  workflow::ArrivingTimeCheck time_check;
  Eigen::VectorXd row(reader.num_columns());
  fmt::memory_buffer line;
  long unflushed = 0;
  auto emit = [&](const Eigen::VectorXd& values) {
    const workflow::StreamStep step = stream.Row(values);
    WriteLine(line, step, estimator->parameters());
    if (o.flush_every > 0 && ++unflushed >= o.flush_every) {
      std::fflush(stdout);
      unflushed = 0;
    }
    CheckStandardOutput();
  };
  while (true) {
    try {
      if (!reader.Next(row)) break;
    } catch (const DataError& e) {
      // A bad row: the reader's "file:line: ..." and the row the output's "t" would have given it.
      const std::string what = e.what();
      const std::string located = reader.path() + ":";
      if (what.starts_with(located) && what.size() > located.size() &&
          std::isdigit(static_cast<unsigned char>(what[located.size()])))
        throw DataError(fmt::format("{} (data row {})", what, stream.rows() + 1));
      throw;
    }
    if (label_column >= 0) {
      if (std::isnan(row(label_column)))
        throw DataError(fmt::format("{}: data row {}: the experiment column '{}' is missing", reader.path(),
                                    stream.rows() + 1, o.experiment_column));
      if (stream.rows() > 0 && row(label_column) != label) stream.Restart();
      label = row(label_column);
    }
    if (time_column >= 0) {
      const std::string& name = reader.names()[static_cast<std::size_t>(time_column)];
      const std::optional<workflow::TimeGap> gap = time_check.Next(row(time_column), reader.rows_read(), name,
                                                                   fmt::format("{}:{}", reader.path(), reader.line()));
      if (gap && o.missing) {
        Eigen::VectorXd missing = Eigen::VectorXd::Constant(row.size(), std::nan(""));
        for (long k = 1; k <= gap->missing; ++k) {
          missing(time_column) = gap->t_before + static_cast<double>(k) * time_check.median_step();
          emit(missing);
        }
      } else if (gap) {
        std::fflush(stdout);
        fmt::print(stderr,
                   "ident stream: time column '{}': gap at data row {} ({} -> {}, {} samples missing; --missing fills "
                   "them as missing samples)\n",
                   name, gap->row, gap->t_before, gap->t_after, gap->missing);
        std::fflush(stderr);
      }
    }
    emit(row);
  }
  if (stream.Finish()) {
    const workflow::StreamStep end{
        .row = stream.rows(), .status = workflow::StreamStatus::kEnd, .weight = std::nan(""), .nu = estimator->nu()};
    WriteLine(line, end, estimator->parameters());
  }
  std::fflush(stdout);
  CheckStandardOutput();
}

}  // namespace

void AddStreamCommand(CLI::App& app) {
  auto o = std::make_shared<StreamCommandOptions>();
  CLI::App* stream = app.add_subcommand(
      "stream", "Estimate on CSV rows as they arrive; print one JSON line per row (theta, weight, status)");
  stream->add_option("DATA", o->data, "CSV with a header: '-' (standard input, the default), a FIFO or a file")
      ->capture_default_str();
  AddExperimentColumnOption(*stream, o->experiment_column);
  o->structure.AddTo(*stream);
  o->estimator.AddTo(*stream);
  stream->add_flag("--missing", o->missing, "Treat empty/NaN/Inf cells as missing samples instead of errors");
  stream
      ->add_option("--flush-every", o->flush_every,
                   "Flush the output after every N lines; 0: only before waiting for more input (the output "
                   "is always flushed then)")
      ->capture_default_str();
  AddDelimiterOption(*stream, o->csv);
  stream->callback([o] { RunStream(*o); });
}

}  // namespace ident::cli
