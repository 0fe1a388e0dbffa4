// ident fit DATA --output y (--input u [--na --nb --nk] | --regressors x1,x2 [--intercept])
//           [--estimator NAME ...] [--split 0.5] [--detrend mean|none] [--missing] [--trace F] [--json]
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <optional>
#include <string_view>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "cli/commands.h"
#include "cli/csv_options.h"
#include "cli/dataset_index.h"
#include "cli/estimator_options.h"
#include "cli/experiment_records.h"
#include "cli/fit_plot.h"
#include "cli/gnuplot.h"
#include "cli/output_file.h"
#include "cli/output_paths.h"
#include "cli/progress.h"
#include "cli/structure_options.h"
#include "cli/time_gaps.h"
#include "common/error.h"
#include "ident/io/csv.h"
#include "ident/io/mat_file.h"
#include "ident/workflow/experiments.h"
#include "ident/workflow/fit.h"
#include "ident/workflow/fit_record.h"
#include "ident/workflow/residual_analysis.h"
#include "ident/workflow/saved_model.h"

namespace ident::cli {
namespace {

constexpr long kInMemoryRows = 1'000'000;

// A data row takes at least two bytes (a cell and its line end; the last line's end may be missing), so a
// file of at most 2·rows bytes holds at most `rows` rows: it is read whole at once, without counting them.
bool MayHoldMoreRows(const std::string& path, long rows) {
  std::error_code error;
  const std::uintmax_t size = std::filesystem::file_size(path, error);
  return error || size > 2 * static_cast<std::uintmax_t>(rows);
}

// Whether a file probably holds more than `rows` rows: its size against the bytes per line of its first and last
// 64 KiB (lines often grow along a record, as its time column does). A guess that only saves a read: the rows read
// whole or counted decide (ReadIfInMemory, CountCsvDataRows).
bool LikelyHoldsMoreRows(const std::string& path, long rows) {
  std::error_code error;
  const std::uintmax_t size = std::filesystem::file_size(path, error);
  std::ifstream in(path, std::ios::binary);
  if (error || !in) return true;  // the row count says why
  io::internal::CountCsvFileOpened();
  constexpr std::uintmax_t kSample = 1 << 16;
  std::string sample(kSample, '\0');
  double bytes = 0, lines = 0;
  for (const std::uintmax_t from : {std::uintmax_t{0}, size > 2 * kSample ? size - kSample : size}) {
    in.seekg(static_cast<std::streamoff>(from));
    in.read(sample.data(), static_cast<std::streamsize>(kSample));
    bytes += static_cast<double>(in.gcount());
    lines += static_cast<double>(std::count(sample.data(), sample.data() + in.gcount(), '\n'));
    in.clear();
  }
  return lines < 2 || static_cast<double>(size) * lines > bytes * static_cast<double>(rows);
}

// The record read whole if it holds at most kInMemoryRows data rows, as CountCsvDataRows counts them (the first
// line of a file without a header is a row of the table, not a data row); else std::nullopt, after reading
// kInMemoryRows + 2 rows at most.
std::optional<io::DataTable> ReadIfInMemory(const std::string& path, const io::CsvOptions& csv) {
  std::optional<io::DataTable> table = io::ReadCsvUpTo(path, kInMemoryRows + 1, csv);
  if (table && table->num_rows() - (table->generated_names ? 1 : 0) > kInMemoryRows) table.reset();
  return table;
}
constexpr int kResidualLags = 20;

struct FitCommandOptions {
  std::vector<std::string> data;  // one record, or one file per experiment
  std::string experiment_column;
  StructureCliOptions structure;
  EstimatorCliOptions estimator;
  double split = 0.5;
  int passes = 1;
  std::string detrend;
  bool missing = false;
  io::CsvOptions csv;  // --delimiter
  bool json = false;
  std::string trace;
  std::string plot;
  std::string save;
  std::string validate;
};

// The model file of --save (ident/workflow/saved_model.h).
workflow::SavedModel ModelToSave(const workflow::RecordFit& fit, const workflow::FitRequest& request,
                                 const std::string& path, const std::vector<ExperimentFile>& files,
                                 const AnyRegressionEstimator& estimator) {
  workflow::SavedModel m;
  m.model = request.model;
  m.structure_name = fit.result.structure;
  m.parameter_names = fit.result.parameter_names;
  m.theta = fit.result.theta;
  m.theta_std = fit.result.theta_std;
  m.covariance = estimator.covariance();
  m.noise_std = fit.result.noise_std;
  m.detrend = request.ResolvedDetrend();
  m.detrend_means = workflow::DetrendMeans(fit);
  m.estimator = fit.result.estimator;
  m.kind = fit.result.kind;
  m.passes = fit.result.passes;
  m.data_path = path;
  m.data_rows = fit.prepared.num_rows();
  // Standard input is gone; several files have no one checksum (each file's is in data_files).
  auto checksum = [](const ExperimentFile& f) {
    if (!f.checksum.empty()) return f.checksum;
    return io::CanReadTwice(f.path) ? workflow::FileChecksum(f.path) : "";
  };
  for (const ExperimentFile& f : files)
    m.data_files.push_back({.path = f.path, .checksum = checksum(f), .rows = f.rows});
  m.data_checksum = files.size() == 1 ? m.data_files.front().checksum : "";
  m.split = request.split;
  m.validation = fit.validation;
  m.validation_scores = fit.result.validation;
  return m;
}

void PrintResiduals(const workflow::ResidualAnalysis& a) {
  auto worst = [](const std::vector<double>& r, int first_lag) {
    std::size_t k = 0;
    for (std::size_t i = 1; i < r.size(); ++i)
      if (std::abs(r[i]) > std::abs(r[k])) k = i;
    return std::make_pair(r[k], static_cast<int>(k) + first_lag);
  };
  if (!a.applies) {
    fmt::print(
        "\n  residual analysis: no correlation tests over lags (a static regression's rows need not be a time "
        "series)\n");
    return;
  }
  const int lags = static_cast<int>(a.autocorrelation.size());
  fmt::print("\n  residual analysis (validation one-step residuals, N = {}, 99 % band ±{:.3f}):\n", a.samples, a.band);
  const auto [r_ee, tau_ee] = worst(a.autocorrelation, 1);
  fmt::print(
      "    whiteness     r_ee(τ), τ = 1..{}: {:2} lags outside, largest {:+.3f} at τ = {}; Q = {:.1f} (1 % limit "
      "{:.1f})\n",
      lags, a.OutsideAuto(), r_ee, tau_ee, a.QAuto(), a.QAutoLimit());
  for (std::size_t i = 0; i < a.input_names.size(); ++i) {
    const auto [r_eu, tau_eu] = worst(a.cross_correlation[i], 0);
    fmt::print(
        "    input {:<7} r_eu(τ), τ = 0..{}: {:2} lags outside, largest {:+.3f} at τ = {}; Q = {:.1f} (1 % limit "
        "{:.1f})\n",
        a.input_names[i], lags, a.OutsideCross(i), r_eu, tau_eu, a.QCross(i), a.QCrossLimit());
  }
  fmt::print("  {}\n", a.Verdict());
}

void PrintReport(const workflow::FitResult& r, const std::string& data, const FitCommandOptions& o,
                 const std::vector<std::pair<std::string, double>>& means = {},
                 const std::vector<workflow::Experiment>& experiments = {}) {
  // --passes asks for at most that many: an estimator declines further passes that cannot change its
  // estimate (RLS on ARX, the batch estimators) or that it does not make (lc:*); the header says so.
  std::string passes = r.passes > 1 ? fmt::format(", {} passes", r.passes) : "";
  if (o.passes > r.passes)
    passes = fmt::format(", {} pass{} of the {} asked: {} makes no further passes", r.passes, r.passes > 1 ? "es" : "",
                         o.passes, r.estimator);
  fmt::print("{}: {} fitted by {} ({}{}, {} detrending)\n", data, r.structure, r.estimator, r.kind, passes, o.detrend);
  const bool separate = !r.validation_data.empty();
  if (o.split == 1 && !separate)
    fmt::print("estimation and validation on all {} rows ({} updates", r.samples_estimation, r.updates);
  else
    fmt::print("estimation rows 1-{} ({} updates", r.samples_estimation, r.updates);
  if (r.rejected) fmt::print(", {} samples rejected as missing/invalid", r.rejected);
  if (r.cleaned) fmt::print(", {} outputs cleaned: the equations that hold them are left out", r.cleaned);
  fmt::print(")");
  if (separate)
    fmt::print(", validation on {} (all {} rows)", r.validation_data, r.samples_validation);
  else if (o.split != 1)
    fmt::print(", validation rows {}-{}", r.samples_estimation + 1, r.samples_estimation + r.samples_validation);
  if (experiments.size() > 1) {
    fmt::print("\n");
    PrintExperiments(experiments);
  }
  fmt::print("\n");
  if (r.time) PrintTimeGaps(stdout, *r.time, o.missing);
  fmt::print("\n  {:<12} {:>14} {:>12}\n", "parameter", "estimate", "std");
  for (int i = 0; i < r.theta.size(); ++i)
    fmt::print("  {:<12} {:>14.6g} {:>12.4g}\n", r.parameter_names[i], r.theta(i), r.theta_std(i));
  // Least squares estimates a standard deviation; the robust and batch estimators a scale (Cauchy's
  // has no standard deviation).
  fmt::print("\n  noise {} {:.4g}\n", r.estimator == "rls" ? "std" : "scale", r.noise_std);
  if (!means.empty()) {
    fmt::print("  detrending means (estimation part, subtracted):");
    for (std::size_t i = 0; i < means.size(); ++i)
      fmt::print("{} {} = {:.6g}", i ? "," : "", means[i].first, means[i].second);
    fmt::print("\n");
  }
  if (r.lock_in) {
    const LockInStatus& l = *r.lock_in;
    fmt::print(
        "  lock-in monitor (window {}, weight threshold {}): flagged at {} update{}, {} restart{}; {:.0f} % of "
        "the last window below the threshold\n",
        l.window, l.threshold, l.flagged, l.flagged == 1 ? "" : "s", l.restarts, l.restarts == 1 ? "" : "s",
        100 * l.low_weight_fraction);
    if (l.start_at_end)
      fmt::print(
          "  robust start from all {} samples when the data ended (no earlier window determined every "
          "coefficient from its inliers)\n",
          l.start_window);
    else if (l.start_update > 0)
      fmt::print("  robust start after update {} from its last {} samples\n", l.start_update, l.start_window);
    for (const RestartEvent& e : l.events)
      if (e.end_of_data)
        fmt::print(
            "    restart at the end of the data (update {}): a restart from the robust fit of all {} samples "
            "kept{}, replayed and refined by further passes, has the higher likelihood and replaces the "
            "estimate\n",
            e.update, e.replayed,
            e.left_out ? fmt::format(" (and {} whose regressor carries a gross output outlier left out)", e.left_out)
                       : "");
      else
        fmt::print("    restart at update {}{}: replayed all {} samples kept{}; low weights {:.0f} % -> {:.0f} %{}\n",
                   e.update, e.pass > 1 ? fmt::format(" of pass {}", e.pass) : "", e.replayed,
                   e.dropped ? fmt::format(" ({} older ones beyond the history limit dropped)", e.dropped) : "",
                   100 * e.low_weight_before, 100 * e.low_weight_after,
                   e.resolved
                       ? ""
                       : " (not a lock-in: the noise is heavier-tailed than the model, or its scale grows along the "
                         "record; next restart waits)");
  }
  // Fit % is undefined (0/0) when the validation output is constant; the JSON has null there.
  auto percent = [](double p) { return std::isfinite(p) ? fmt::format("{:.2f} %", p) : std::string("undefined"); };
  fmt::print("  validation fit: one-step {} (RMS {:.4g})", percent(r.validation.one_step), r.validation.rms_one_step);
  if (r.validation.simulation)
    fmt::print(", simulation {} (RMS {:.4g})", percent(*r.validation.simulation), *r.validation.rms_simulation);
  if (r.validation.simulation_diverged_at)
    fmt::print(", simulation: unstable model (simulation diverged at row {})", *r.validation.simulation_diverged_at);
  fmt::print("\n");
}

void RunFit(const FitCommandOptions& o) {
  std::vector<std::string> paths;
  for (const std::string& d : o.data) paths.push_back(ResolveDataPath(d));
  std::vector<NamedPath> inputs = {{"--prior file", o.estimator.prior_file}};
  for (const std::string& p : paths) inputs.push_back({"input data file", p});
  CheckOutputPaths({{"--trace", o.trace}, {"--plot", o.plot}, {"--save", o.save}}, inputs);
  if (!o.plot.empty()) CheckPlotFileName(o.plot);
  const io::CsvOptions csv{.missing_as_nan = o.missing, .delimiter = o.csv.delimiter};
  // Several experiments (several files, or an experiment column) are read into one table in memory.
  const bool experiments = paths.size() > 1 || !o.experiment_column.empty();
  std::vector<workflow::Experiment> experiment_list;
  std::vector<ExperimentFile> files;
  std::optional<io::DataTable> once;
  if (experiments) {
    ExperimentRecords records = ReadExperimentRecords(paths, o.experiment_column, csv);
    once = std::move(records.table);
    experiment_list = std::move(records.experiments);
    files = std::move(records.files);
  }
  const std::string path = experiments ? once->source : paths.front();
  // Standard input, a pipe, a device or a .mat file is read once, into memory; a regular file is first checked by
  // its header, then read whole if it probably fits, else counted, and streamed when long. Records up to
  // kInMemoryRows rows are read whole, for the time column's check, the residual analysis and plots; longer
  // ones stream through the estimator in constant memory (without them).
  // --save records the file's checksum from its bytes as they are read whole: one read, and the checksum of
  // exactly the bytes fitted.
  io::CsvOptions whole_csv = csv;
  workflow::Checksum checksum;
  const bool checksum_as_read = !o.save.empty() && !experiments && io::CanReadTwice(path) && !io::IsMatFile(path);
  if (checksum_as_read) whole_csv.on_bytes = [&checksum](std::string_view bytes) { checksum.Add(bytes); };
  if (!once && (!io::CanReadTwice(path) || io::IsMatFile(path) || !MayHoldMoreRows(path, kInMemoryRows)))
    once = io::ReadDataFile(path, whole_csv);
  std::unique_ptr<workflow::DataSource> source =
      o.structure.MakeSource(once ? once->names : io::CsvReader(path, csv).names(), path);
  const bool may_stream = !once && o.plot.empty() && o.save.empty() && o.validate.empty();
  // Read whole at once, not counted first (the read stops early if the record is longer after all).
  if (may_stream && !LikelyHoldsMoreRows(path, kInMemoryRows)) once = ReadIfInMemory(path, csv);
  workflow::FitRequest request;
  request.model = o.structure;
  request.estimator = o.estimator;
  request.split = o.split;
  request.passes = o.passes;
  request.detrend = o.detrend;
  request.residual_lags = kResidualLags;
  const bool counted = may_stream && !once;
  // Counted and, if long, the estimation part's means taken, in one read (workflow::ScanCsvFirstPass); with time
  // gaps to fill, or where that pass does not apply, counted by a pass of its own.
  std::optional<workflow::CsvFirstPass> first;
  if (counted && !o.missing) {
    const workflow::FitPlan planned = workflow::PlanFitOptions(request, source->num_parameters());
    first = workflow::ScanCsvFirstPass(path, csv, *source, planned.options,
                                       planned.scaled_prior && source->affine_in_rows());
  }
  const long data_lines = first ? first->data_lines : counted ? workflow::CountCsvDataRows(path) : 0;
  const bool streamed = counted && data_lines > kInMemoryRows;
  if (!streamed) first.reset();
  if (!streamed && !once) once = io::ReadDataFile(path, whole_csv);
  std::optional<workflow::TimeCheck> time;
  if (!experiments)  // as read, before gaps are filled
    files = {{path, once ? once->num_rows() : 0, checksum_as_read ? checksum.Hex() : ""}};
  if (once && !experiments)  // a time column restarts in each experiment
    time = workflow::CheckRecordTime(*once, source->used_columns(), o.missing);
  // Streamed: the gaps to fill are found in a pass of their own; otherwise the estimation pass checks the time.
  if (streamed && o.missing) time = workflow::ScanCsvTime(path, csv, source->used_columns());
  // The record's length first: building an estimator costs O(rho^3) for large orders.
  workflow::FitOptions length_check;
  length_check.split = o.split;
  std::optional<workflow::CsvLayout> layout;
  if (first)
    layout = first->layout;
  else if (!once)
    layout = workflow::CheckCsvLayout(path, csv, *source, length_check, data_lines, time ? &*time : nullptr);
  const long estimation_rows =
      once ? workflow::CheckRecordLength(once->num_rows(), *source, length_check, path) : layout->estimation.count;
  workflow::FitPlan plan = workflow::PlanFit(request, source->num_parameters(), estimation_rows);
  // Progress on stderr after 2 s: rows of the estimation part, per pass (a pass starts again at its first row).
  Progress progress("fit");
  // The state lives out here: the options, and with them this function, are copied for each pass.
  int pass = 1, last = -1;
  plan.options.on_row = [&progress, &pass, &last, estimation_rows, passes = o.passes](int row) {
    if (row <= last) ++pass;
    last = row;
    progress.Report(row + 1, estimation_rows, "estimation rows", passes > 1 ? pass : 0);
  };
  // The trace and the plot go to temporary files, renamed onto their names only after the whole fit has
  // succeeded (cli/output_file.h): a fit that fails, e.g. on a bad row late in a streamed record, leaves
  // every existing file as it is. The report is printed after the renames, so a failed write leaves
  // stdout empty.
  std::optional<OutputFile> trace, plot, save;
  if (!o.trace.empty()) {
    trace.emplace(o.trace, "--trace file");
    plan.options.trace = trace->stream();
  }
  if (!o.plot.empty()) plot.emplace(o.plot, "--plot file");
  if (!o.save.empty()) save.emplace(o.save, "--save file");
  auto commit_outputs = [&] {
    for (std::optional<OutputFile>* f : {&trace, &plot, &save})
      if (*f) (*f)->Close();
    for (std::optional<OutputFile>* f : {&trace, &plot, &save})
      if (*f) (*f)->Commit();
  };
  if (streamed) {
    const workflow::FitResult result =
        first ? workflow::FitCsvFile(path, csv, *source, plan, *first)
              : workflow::FitCsvFile(path, csv, *source, plan, *layout, time ? &*time : nullptr);
    commit_outputs();
    if (o.json) {
      std::cout << workflow::FitJson(result, path, o.split, o.detrend, nullptr, nullptr).dump(2) << "\n";
    } else {
      PrintReport(result, path, o);
      fmt::print("\n  residual analysis: skipped (record of more than {} rows, streamed)\n", kInMemoryRows);
    }
    return;
  }
  ParameterHistory history;
  if (!o.plot.empty()) {
    history.theta.resize(static_cast<std::size_t>(source->num_parameters()));
    plan.options.on_update = [&history](int row, const StepReport& step, const AnyRegressionEstimator& e) {
      history.t.push_back(row + 1);
      history.weight.push_back(step.nu * step.weight);
      const Eigen::VectorXd theta = e.parameters();
      for (int i = 0; i < theta.size(); ++i) history.theta[static_cast<std::size_t>(i)].push_back(theta(i));
    };
  }
  workflow::RecordFit fit = workflow::FitTable(std::move(*once), *source, plan, kResidualLags);
  fit.result.time = time;
  if (experiments) fit.experiments = experiment_list;
  if (!o.validate.empty()) {
    const std::string validation_path = ResolveDataPath(o.validate);
    io::DataTable record = io::ReadDataFile(validation_path, csv);
    if (!o.experiment_column.empty()) workflow::LabelExperiments(record, o.experiment_column);
    workflow::ValidateOn(fit, std::move(record), validation_path, request.model, kResidualLags);
  }
  if (plot) PlotFit(*plot, fit, *source, history);
  if (save) save->Write(ModelToSave(fit, request, path, files, *plan.estimator).ToJson().dump(1) + "\n");
  commit_outputs();
  const workflow::ResidualAnalysis* residuals = fit.residuals ? &*fit.residuals : nullptr;
  if (o.json) {
    const auto means = workflow::DetrendMeans(fit);
    std::cout << workflow::FitJson(fit.result, path, o.split, o.detrend, residuals, &means, &fit.experiments).dump(2)
              << "\n";
  } else {
    PrintReport(fit.result, path, o, workflow::DetrendMeans(fit), fit.experiments);
    if (residuals) PrintResiduals(*residuals);
  }
}

}  // namespace

void AddFitCommand(CLI::App& app) {
  auto o = std::make_shared<FitCommandOptions>();
  CLI::App* fit = app.add_subcommand("fit", "Fit a model to recorded data with a recursive estimator");
  AddDataFilesOptions(*fit, o->data, o->experiment_column);
  o->structure.AddTo(*fit, /*require_output=*/false);
  o->estimator.AddTo(*fit);
  fit->add_option("--split", o->split, "Fraction of rows used for estimation; 1 = estimate and validate on all")
      ->capture_default_str();
  fit->add_option("--passes", o->passes,
                  "Passes over the estimation part: each further pass re-runs the recursion from the previous "
                  "pass's estimate (cauchy, student; rls and the batch estimators need one)")
      ->capture_default_str();
  fit->add_option("--detrend", o->detrend,
                  "Subtract the estimation-part means (mean) or not (none); default mean, none with --intercept")
      ->check(CLI::IsMember({"mean", "none"}));
  AddMissingOption(*fit, o->missing);
  fit->add_option("--trace", o->trace, "Write one CSV row per update: t,nu,beta,pred_err,theta1..,Dy");
  fit->add_option("--plot", o->plot,
                  "Draw measured vs one-step and simulated output (validation, data units), the parameter "
                  "trajectories, the robust weights and the residual correlations into FILE.svg or FILE.png "
                  "(needs gnuplot)");
  fit->add_option("--validate", o->validate,
                  "Validate on this separate record (CSV or bundled name) instead of the rest of DATA; "
                  "--split then defaults to 1");
  fit->add_option("--save", o->save,
                  "Write the fitted model (structure, theta, covariance, detrending means, ...) as JSON for "
                  "ident predict");
  fit->add_flag("--json", o->json, "Print one JSON object instead of the report");
  AddDelimiterOption(*fit, o->csv);
  auto* split_option = fit->get_option("--split");
  fit->callback([o, split_option] {
    // Without structure options a bundled record takes its suggested structure and split, as in compare.
    const std::optional<DatasetInfo> dataset = FindDataset(o->data.front());
    if (dataset && !o->structure.Given()) {
      o->structure = o->structure.WithDefaultsFrom(dataset->structure);
      if (split_option->count() == 0) o->split = dataset->split;
    }
    if (o->structure.output.empty()) throw CLI::RequiredError("--output");
    if (o->detrend.empty()) o->detrend = o->structure.intercept ? "none" : "mean";
    if (!o->validate.empty() && split_option->count() == 0) o->split = 1;  // all of DATA estimates
    RunFit(*o);
  });
}

}  // namespace ident::cli
