// ident predict MODEL.json DATA... [--experiment-column NAME] [--rows A:B] [--horizon K] [--simulate] [--json]
// Predictions of a saved model (ident fit --save, ident/workflow/saved_model.h) on a record with the same
// columns, in physical units: the model's detrending means are subtracted from the data and added back to
// the predictions. Scores as ident fit scores its validation part (workflow::Score): on the rows of the
// fit's validation part this reproduces the fit's figures exactly. Several experiments (several files, an
// experiment column) are predicted as ident fit scores them: each restarts the regressors and the simulation.
#include <cmath>
#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "cli/commands.h"
#include "cli/csv_options.h"
#include "cli/estimator_options.h"
#include "cli/experiment_records.h"
#include "cli/progress.h"
#include "cli/time_gaps.h"
#include "common/error.h"
#include "ident/io/csv.h"
#include "ident/io/mat_file.h"
#include "ident/workflow/json_number.h"
#include "ident/workflow/order_selection.h"
#include "ident/workflow/predictions.h"
#include "ident/workflow/saved_model.h"

namespace ident::cli {
namespace {

struct PredictOptions {
  std::string model, rows, experiment_column;
  std::vector<std::string> data;  // one record, or one file per experiment
  int horizon = 1;
  bool simulate = false, json = false, missing = false;
  io::CsvOptions csv;
};

// Fit % and RMS of `y_hat` against `y` over the finite pairs (workflow::Score's definition).
std::pair<double, double> FitOf(const std::vector<double>& y, const std::vector<double>& y_hat) {
  double mean = 0, n = 0;
  for (std::size_t i = 0; i < y.size(); ++i)
    if (std::isfinite(y_hat[i]) && std::isfinite(y[i])) mean += y[i], ++n;
  mean /= n;
  double ee = 0, yy = 0;
  for (std::size_t i = 0; i < y.size(); ++i)
    if (std::isfinite(y_hat[i]) && std::isfinite(y[i])) {
      ee += (y[i] - y_hat[i]) * (y[i] - y_hat[i]);
      yy += (y[i] - mean) * (y[i] - mean);
    }
  return {100 * (1 - std::sqrt(ee / yy)), std::sqrt(ee / n)};
}

void RunPredict(const PredictOptions& o) {
  const workflow::SavedModel m = workflow::SavedModel::Read(o.model);
  std::vector<std::string> paths;
  for (const std::string& d : o.data) paths.push_back(ResolveDataPath(d));
  // Progress on stderr after 2 s: the reading of a single file, then the rows written.
  Progress progress("predict");
  io::CsvOptions csv{.missing_as_nan = o.missing, .delimiter = o.csv.delimiter};
  if (paths.size() == 1) csv.on_read = ReadingProgress(progress, paths.front());
  ExperimentRecords records = ReadExperimentRecords(paths, o.experiment_column, csv);
  io::DataTable& table = records.table;
  const std::string path = records.name;
  std::unique_ptr<workflow::DataSource> source = m.model.MakeSource(table.names, path);
  // The time column of a single record (a time column restarts in each experiment); --missing fills its gaps.
  std::optional<workflow::TimeCheck> time;
  if (!records.several) time = workflow::CheckRecordTime(table, source->used_columns(), o.missing);
  IDENT_REQUIRE(source->num_parameters() == m.theta.size(), "{}: theta has {} entries; {} needs {}", o.model,
                m.theta.size(), source->structure(), source->num_parameters());
  IDENT_REQUIRE(o.horizon >= 1, "--horizon {}; need 1 or more", o.horizon);
  const Eigen::VectorXd measured = table.Column(m.model.output);  // as recorded, for the CSV
  double output_mean = 0;
  for (const auto& [name, mean] : m.detrend_means) {
    table.values.col(table.ColumnIndex(name)).array() -= mean;
    if (name == m.model.output) output_mean = mean;
  }
  workflow::Segment segment{0, table.num_rows()};
  if (!o.rows.empty()) {
    const auto [a, b] = workflow::OrderGrid::ParseRange(o.rows, "--rows");
    IDENT_REQUIRE(a >= 1 && b <= table.num_rows(), "--rows {}: {} has rows 1-{}", o.rows, path, table.num_rows());
    segment = {a - 1, b - a + 1};
  }
  IDENT_REQUIRE(segment.count > source->first_regression_index(),
                "--rows {}: {} rows are too few for {} (the first {} have no regressor)", o.rows, segment.count,
                source->structure(), source->first_regression_index());
  const workflow::SegmentPredictions p = workflow::PredictSegment(table, segment, *source, m.theta);
  std::vector<double> k_step;
  if (o.horizon > 1) {
    if (m.model.polynomial()) {
      k_step = workflow::PredictKSteps(table, segment, *source, m.theta, o.horizon);
    } else if (source->dynamic()) {
      std::vector<int> inputs;
      for (const auto& name : m.model.inputs) inputs.push_back(table.ColumnIndex(name));
      const std::size_t count = m.model.inputs.size();
      auto per_input = [count](const std::vector<int>& v) {
        return v.size() == count ? v : std::vector<int>(count, v[0]);
      };
      const models::ArxStructure arx(m.model.na, per_input(m.model.nb), per_input(m.model.nk));
      k_step =
          workflow::PredictKSteps(table, segment, arx, table.ColumnIndex(m.model.output), inputs, m.theta, o.horizon);
    } else {
      k_step = p.one_step;  // a static model has no dynamics: every horizon is the one-step prediction
    }
  }
  if (o.json) {
    const workflow::FitScores scores = workflow::Score(table, segment, *source, m.theta);
    nlohmann::ordered_json j;
    j["model"] = o.model;
    j["data"] = path;
    j["rows"] = {segment.first + 1, segment.first + segment.count};
    j["samples"] = scores.scored;
    j["horizon"] = o.horizon;
    j["fit_percent"] = {{"one_step", workflow::FiniteOrNull(scores.one_step)},
                        {"simulation", scores.simulation ? workflow::FiniteOrNull(*scores.simulation) : nullptr}};
    j["rms"] = {{"one_step", workflow::FiniteOrNull(scores.rms_one_step)},
                {"simulation", scores.rms_simulation ? workflow::FiniteOrNull(*scores.rms_simulation) : nullptr}};
    j["simulation_diverged_at"] =
        scores.simulation_diverged_at ? nlohmann::ordered_json(*scores.simulation_diverged_at) : nullptr;
    if (!k_step.empty()) {
      const auto [fit, rms] = FitOf(p.measured, k_step);
      j["k_step"] = {{"fit_percent", workflow::FiniteOrNull(fit)}, {"rms", workflow::FiniteOrNull(rms)}};
    } else {
      j["k_step"] = nullptr;
    }
    j["experiments"] = workflow::ExperimentsJson(records.experiments);
    j["time_gaps"] = workflow::TimeGapsJson(time);
    std::cout << j.dump(2) << "\n";
    return;
  }
  // One CSV row per row of the segment, in physical units; the time column's gaps on stderr, outside the CSV.
  if (time) PrintTimeGaps(stderr, *time, o.missing);
  // With several experiments a last column names each row's.
  std::vector<std::string> experiment_of;
  if (records.experiments.size() > 1)
    for (const workflow::Experiment& e : records.experiments) experiment_of.resize(e.first + e.count, e.name);
  fmt::print("row,y,one_step,residual{}{}{}\n", k_step.empty() ? "" : fmt::format(",k{}_step", o.horizon),
             o.simulate && !p.simulation.empty() ? ",simulation" : "", experiment_of.empty() ? "" : ",experiment");
  for (std::size_t i = 0; i < p.rows.size(); ++i) {
    // Shortest round-trip digits; the residual is y − ŷ in the detrended unit (no rounding from the mean).
    const double y = measured(p.rows[i] - 1), y1 = p.one_step[i] + output_mean;
    fmt::print("{},{},{},{}", p.rows[i], y, y1, p.measured[i] - p.one_step[i]);
    if (!k_step.empty()) fmt::print(",{}", k_step[i] + output_mean);
    if (o.simulate && !p.simulation.empty()) fmt::print(",{}", p.simulation[i] + output_mean);
    if (!experiment_of.empty()) fmt::print(",{}", experiment_of[static_cast<std::size_t>(p.rows[i] - 1)]);
    fmt::print("\n");
    progress.Report(static_cast<long>(i + 1), static_cast<long>(p.rows.size()), "rows written");
  }
}

}  // namespace

void AddPredictCommand(CLI::App& app) {
  auto o = std::make_shared<PredictOptions>();
  CLI::App* cmd =
      app.add_subcommand("predict", "Predict or simulate with a saved model (ident fit --save) on a record");
  cmd->add_option("MODEL", o->model, "Model file written by ident fit --save")->required();
  AddDataFilesOptions(*cmd, o->data, o->experiment_column,
                      "CSV file with the model's columns, or a bundled dataset's name");
  cmd->add_option("--rows", o->rows, "Rows A:B (1-based) to predict and score; default all");
  cmd->add_option("--horizon", o->horizon, "Also the K-step-ahead prediction (outputs after t-K predicted)")
      ->capture_default_str();
  cmd->add_flag("--simulate", o->simulate, "Also the simulated output (the model's own past outputs)");
  AddMissingOption(*cmd, o->missing);
  cmd->add_flag("--json", o->json, "Print fit % and RMS (one_step, simulation, k_step) as JSON instead of the CSV");
  AddDelimiterOption(*cmd, o->csv);
  cmd->callback([o] { RunPredict(*o); });
}

}  // namespace ident::cli
