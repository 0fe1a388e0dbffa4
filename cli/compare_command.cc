// ident compare DATA... [--experiment-column NAME] [--estimators rls,cauchy,student:3] [--outliers RATE:SIZE[:SEED]] [--trials N]
//               [structure options] [estimator options] [--split F] [--detrend mean|none] [--json|--csv]
// Without structure options a bundled dataset uses its suggested structure and split (datasets/index.json).
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <iostream>
#include <limits>
#include <memory>
#include <optional>
#include <thread>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <nlohmann/json.hpp>

#include "cli/commands.h"
#include "cli/csv_options.h"
#include "cli/dataset_index.h"
#include "cli/estimator_options.h"
#include "cli/experiment_records.h"
#include "cli/gnuplot.h"
#include "cli/output_file.h"
#include "cli/output_paths.h"
#include "cli/structure_options.h"
#include "cli/time_gaps.h"
#include "common/error.h"
#include "ident/io/csv.h"
#include "ident/io/mat_file.h"
#include "ident/workflow/compare_record.h"

namespace ident::cli {
namespace {

struct CompareCommandOptions {
  std::vector<std::string> data;  // one record, or one file per experiment
  std::string experiment_column;
  bool missing = false;
  io::CsvOptions read;  // --delimiter
  StructureCliOptions structure;
  EstimatorCliOptions estimator;
  std::vector<std::string> estimators{"rls,cauchy,student:3"};  // comma-separated lists, split by RunCompare
  std::string outliers = "0.05:20:1";
  int trials = 1;
  int jobs = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  int passes = 1;
  std::optional<double> split;
  std::string detrend;
  bool json = false, csv = false;
  std::string plot;
};

// One panel per score (one-step fit %, θ distance): per estimator the trials' values as points spread
// sideways (a strip plot) and, from 5 trials on, their box plot (quartiles, median, whiskers to the last
// values within 1.5 interquartile ranges).
PlotPanel CompareScorePanel(const workflow::CompareResult& r, std::string title, std::string ylabel,
                            std::vector<double> workflow::EstimatorScore::*per_trial, std::optional<double> reference,
                            const std::string& reference_title) {
  PlotPanel panel{std::move(title), "", std::move(ylabel), {}};
  const double n = static_cast<double>(r.scores.size());
  panel.xrange = PlotRange{0.4, n + 0.6};
  if (reference)
    panel.series.push_back(
        {reference_title, {0.4, n + 0.6}, {*reference, *reference}, "lines lw 1.5 dt 2 lc rgb 'black'"});
  bool first_box = true;
  double low = reference.value_or(std::numeric_limits<double>::infinity());
  double high = reference.value_or(-std::numeric_limits<double>::infinity());
  for (std::size_t i = 0; i < r.scores.size(); ++i) {
    const workflow::EstimatorScore& s = r.scores[i];
    const double x0 = static_cast<double>(i + 1);
    panel.xtics.emplace_back(x0, s.estimator);
    const std::vector<double>& values = s.*per_trial;
    PlotSeries points{"", {}, {}, fmt::format("points pt 7 ps {} lc {}", values.size() < 5 ? 1.6 : 0.7, i + 1)};
    for (std::size_t k = 0; k < values.size(); ++k) {
      if (!std::isfinite(values[k])) continue;
      // Golden-ratio offsets spread the points evenly over ±0.15 without randomness.
      const double frac = std::fmod(0.6180339887498949 * static_cast<double>(k), 1.0);
      points.x.push_back(values.size() > 1 ? x0 + 0.3 * (frac - 0.5) : x0);
      points.y.push_back(values[k]);
      low = std::min(low, values[k]);
      high = std::max(high, values[k]);
    }
    if (points.y.empty()) continue;
    if (points.y.size() >= 5) {
      panel.series.push_back({first_box ? "box: quartiles, median" : "", std::vector<double>(points.y.size(), x0),
                              points.y, "boxplot lw 1.2 lc rgb 'black'"});
      first_box = false;
    }
    panel.series.push_back(std::move(points));
  }
  if (low <= high) {  // a margin, so that no point sits on the frame
    const double margin = std::max(0.08 * (high - low), 1e-3 * std::max(1.0, std::abs(high)));
    panel.yrange = PlotRange{low - margin, high + margin};
  }
  return panel;
}

void PlotCompare(OutputFile& out, const workflow::CompareResult& r, const workflow::OutlierSpec& spec, int trials) {
  const std::string setting = r.outliers_per_trial > 0
                                  ? fmt::format("{} outliers of ±{:g}σ, {} trial{}", r.outliers_per_trial, spec.size,
                                                trials, trials == 1 ? "" : "s")
                                  : fmt::format("no outliers, {} trial{}", trials, trials == 1 ? "" : "s");
  const PlotPanel fit = CompareScorePanel(
      r, fmt::format("{}: one-step validation fit per trial ({})", r.structure, setting), "one-step fit %",
      &workflow::EstimatorScore::one_step_per_trial, r.reference.one_step, "clean-data LS");
  const PlotPanel distance =
      CompareScorePanel(r, "distance to the clean-data least-squares estimate, ||θ̂ − θ_LS|| / ||θ_LS||, per trial",
                        "θ distance", &workflow::EstimatorScore::theta_distance_per_trial, 0.0, "0 = clean-data LS");
  RenderPlot(out, {fit, distance}, PlotSize{.width = 1000, .height_per_panel = 360});
}

void PrintCsv(const workflow::CompareResult& r) {
  fmt::print(
      "estimator,fit_one_step,fit_one_step_std,fit_one_step_min,fit_one_step_median,fit_one_step_max,"
      "fit_simulation,fit_simulation_std,theta_distance,theta_distance_std,ns_per_update");
  for (const auto& name : r.parameter_names) fmt::print(",{}", name);
  fmt::print("\n");
  for (const workflow::EstimatorScore& s : r.scores) {
    auto sim = [&](double v) { return s.has_simulation ? fmt::format("{:.6g}", v) : std::string(); };
    fmt::print("{},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g},{},{},{:.6g},{:.6g},{:.4g}", s.estimator, s.one_step.mean,
               s.one_step.std, s.one_step.min, s.one_step.median, s.one_step.max, sim(s.simulation.mean),
               sim(s.simulation.std), s.theta_distance.mean, s.theta_distance.std, s.ns_per_update);
    for (int i = 0; i < s.theta.size(); ++i) fmt::print(",{:.9g}", s.theta(i));
    fmt::print("\n");
  }
}

std::string Cell(const workflow::Spread& s, int trials, const char* format) {
  if (std::isnan(s.mean)) return "failed";
  const std::string mean = fmt::format(fmt::runtime(format), s.mean);
  return trials > 1 ? mean + " ± " + fmt::format(fmt::runtime(format), s.std) : mean;
}

void PrintTable(const workflow::CompareResult& r, const std::string& name, const workflow::OutlierSpec& spec,
                int trials, const std::string& cleaning, bool missing) {
  fmt::print("{}: {}, estimation rows {}-{}, validation rows {}-{}\n", name, r.structure, r.estimation.first + 1,
             r.estimation.first + r.estimation.count, r.validation.first + 1, r.validation.first + r.validation.count);
  if (r.experiments.size() > 1) {
    PrintExperiments(r.experiments);
    fmt::print("\n");
  }
  if (r.time) PrintTimeGaps(stdout, *r.time, missing);
  if (r.outliers_per_trial > 0)
    fmt::print(
        "outliers: {} of the {} estimation samples ({:g} %) moved by ±{:g}σ (σ = {:.4g}, the clean LS residual "
        "std), seed {}{}\n",
        r.outliers_per_trial, r.estimation.count, 100 * spec.rate, spec.size, r.sigma, spec.seed,
        trials > 1 ? fmt::format("…{} ({} trials: mean ± std)", spec.seed + trials - 1, trials) : "");
  else
    fmt::print("no outliers injected\n");
  if (cleaning == "on") fmt::print("regressor cleaning on (outputs flagged by the estimator are cleaned)\n");
  // An ARMAX/OE/BJ reference whose C or F is unstable has no one-step predictor (NaN): said in words.
  if (std::isfinite(r.reference.one_step))
    fmt::print("clean-data least squares: one-step fit {:.2f} %", r.reference.one_step);
  else
    fmt::print("clean-data least squares: one-step fit undefined (its predictor is unstable)");
  if (r.reference.simulation) fmt::print(", simulation fit {:.2f} %", *r.reference.simulation);
  fmt::print("\n\n");
  const int w = trials > 1 ? 16 : 10;
  fmt::print("  {:<14} {:<9} {:>{}} {:>{}} {:>{}} {:>11}\n", "estimator", "kind", "one-step %", w, "simulation %", w,
             "θ distance", w, "ns/update");
  for (const workflow::EstimatorScore& s : r.scores) {
    fmt::print("  {:<14} {:<9} {:>{}} {:>{}} {:>{}} {:>11.0f}\n", s.estimator, s.kind,
               Cell(s.one_step, trials, "{:.2f}"), w, s.has_simulation ? Cell(s.simulation, trials, "{:.2f}") : "-", w,
               Cell(s.theta_distance, trials, "{:.3f}"), w, s.ns_per_update);
  }
  for (const workflow::EstimatorScore& s : r.scores)
    if (s.failed_trials > 0)
      fmt::print("\n  {} failed in {} of {} trials (left out of its figures); first, {}\n", s.estimator,
                 s.failed_trials, trials, s.failure);
  fmt::print(
      "\n  fit % = 100·(1 − ‖y − ŷ‖/‖y − mean y‖) on the clean validation rows (100 = perfect; one-step uses\n"
      "  measured past outputs, simulation the model's own); θ distance = ‖θ̂ − θ_LS‖/‖θ_LS‖ to the clean-data\n"
      "  least-squares θ (0 = identical). Sorted by one-step fit.\n");
}

void ProgressBar(int done, int total) {
  const int width = 30;
  const int filled = total > 0 ? done * width / total : width;
  fmt::print(stderr, "\r[{}{}] {}/{} runs", std::string(static_cast<std::size_t>(filled), '#'),
             std::string(static_cast<std::size_t>(width - filled), '.'), done, total);
  if (done == total) fmt::print(stderr, "\r{}\r", std::string(width + 20, ' '));
  std::fflush(stderr);
}

// Without a terminal (a log, a pipe): once the comparison has run 2 s, one line per 10 % of the runs.
std::function<void(int, int)> ProgressLines() {
  const auto start = std::chrono::steady_clock::now();
  return [start, reported = 0](int done, int total) mutable {
    const int tenth = total > 0 ? 10 * done / total : 10;
    if (tenth <= reported) return;
    reported = tenth;
    if (std::chrono::steady_clock::now() - start < std::chrono::seconds(2)) return;
    fmt::print(stderr, "ident compare: {} % ({} of {} runs)\n", 10 * tenth, done, total);
    std::fflush(stderr);
  };
}

void RunCompare(CompareCommandOptions& o) {
  std::vector<std::string> paths;
  std::vector<NamedPath> inputs = {{"--prior file", o.estimator.prior_file}};
  for (const std::string& d : o.data) {
    paths.push_back(ResolveDataPath(d));
    inputs.push_back({"input data file", paths.back()});
  }
  const std::optional<DatasetInfo> dataset = FindDataset(o.data.front());
  IDENT_REQUIRE(dataset.has_value() || o.structure.Given(),
                "'{}' is not a bundled dataset with a suggested structure; give --output and --input (or --regressors)",
                o.data.front());
  const StructureCliOptions structure = dataset ? o.structure.WithDefaultsFrom(dataset->structure) : o.structure;
  const double split = o.split.value_or(dataset && !o.structure.Given() ? dataset->split : 0.5);
  IDENT_REQUIRE(!structure.output.empty(), "give --output (the output column)");
  const std::string detrend = !o.detrend.empty() ? o.detrend : structure.intercept ? "none" : "mean";
  const workflow::OutlierSpec spec = workflow::OutlierSpec::Parse(o.outliers);
  CheckOutputPaths({{"--plot", o.plot}}, inputs);
  std::optional<OutputFile> plot;  // renamed onto --plot only when the comparison and the plot succeed
  if (!o.plot.empty()) {
    CheckPlotFileName(o.plot);
    plot.emplace(o.plot, "--plot file");
  }

  workflow::CompareRequest request;
  request.model = structure;
  request.options = o.estimator;
  request.estimators = o.estimators;
  request.outliers = spec;
  request.trials = o.trials;
  IDENT_REQUIRE(o.jobs >= 1 && o.jobs <= 1024, "--jobs {}; need 1 <= jobs <= 1024", o.jobs);
  request.jobs = o.jobs;
  request.passes = o.passes;
  request.split = split;
  request.detrend = detrend;
  request.progress = isatty(STDERR_FILENO) ? std::function<void(int, int)>(ProgressBar) : ProgressLines();
  // Several experiments (several files, an experiment column) in one table, as ident fit reads them; the time
  // column of a single record is checked (its gaps filled with --missing).
  ExperimentRecords records =
      ReadExperimentRecords(paths, o.experiment_column, {.missing_as_nan = o.missing, .delimiter = o.read.delimiter});
  const std::string path = records.several ? records.name : paths.front();
  std::optional<workflow::TimeCheck> time;
  if (!records.several)
    time = workflow::CheckRecordTime(records.table, structure.MakeSource(records.table.names, path)->used_columns(),
                                     o.missing);
  workflow::CompareResult result = workflow::CompareRecord(std::move(records.table), path, request);
  if (records.several) result.experiments = records.experiments;
  result.time = time;
  const std::string name = dataset && !records.several ? dataset->name : path;
  if (plot) {
    PlotCompare(*plot, result, spec, o.trials);
    plot->Commit();
  }
  if (o.json)
    std::cout << workflow::CompareJson(result, path, spec, o.trials, structure.clean_regressors).dump(2) << "\n";
  else if (o.csv)
    PrintCsv(result);
  else
    PrintTable(result, name, spec, o.trials, structure.clean_regressors, o.missing);
}

}  // namespace

void AddCompareCommand(CLI::App& app) {
  auto o = std::make_shared<CompareCommandOptions>();
  CLI::App* cmd = app.add_subcommand(
      "compare", "Compare estimators on a record with injected outliers, scored on its clean validation part");
  AddDataFilesOptions(*cmd, o->data, o->experiment_column);
  AddMissingOption(*cmd, o->missing);
  cmd->add_option("--estimators", o->estimators,
                  fmt::format("Comma-separated estimators ({}; dof as 'student:3')",
                              fmt::join(RegressionEstimatorNames(), ", ")))
      ->capture_default_str();
  cmd->add_option("--outliers", o->outliers,
                  "RATE:SIZE[:SEED]: fraction of estimation samples, size in clean LS residual stds, seed; or none")
      ->capture_default_str();
  cmd->add_option("--trials", o->trials, "Repeat with seeds SEED, SEED+1, …; report mean and spread")
      ->capture_default_str();
  cmd->add_option("--jobs", o->jobs,
                  "Threads the trials run on (default: every core); the results do not depend on it");
  o->structure.AddTo(*cmd, /*require_output=*/false);
  o->estimator.AddTo(*cmd, /*with_estimator=*/false);
  cmd->add_option("--passes", o->passes,
                  "Passes over the estimation part for the robust recursive estimators (see ident fit --passes)")
      ->capture_default_str();
  cmd->add_option("--split", o->split, "Fraction of rows used for estimation (default: the dataset's, else 0.5)");
  cmd->add_option("--detrend", o->detrend, "Subtract the estimation-part means (mean) or not (none)")
      ->check(CLI::IsMember({"mean", "none"}));
  cmd->add_option(
      "--plot", o->plot,
      "Draw the one-step fit % and θ distance of every trial per estimator into FILE.svg or FILE.png (needs gnuplot)");
  auto* json = cmd->add_flag("--json", o->json, "Print one JSON object (schema in docs/reference/cli.md)");
  cmd->add_flag("--csv", o->csv, "Print one CSV row per estimator")->excludes(json);
  AddDelimiterOption(*cmd, o->read);
  cmd->callback([o] { RunCompare(*o); });
}

}  // namespace ident::cli
