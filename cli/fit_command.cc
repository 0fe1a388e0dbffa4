// ident fit DATA --output y (--input u [--na --nb --nk] | --regressors x1,x2 [--intercept])
//           [--estimator NAME ...] [--split 0.5] [--detrend mean|none] [--missing] [--trace F] [--json]
#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>
#include <optional>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <nlohmann/json.hpp>

#include "common/error.h"
#include "ident/io/csv.h"
#include "ident/workflow/fit.h"
#include "ident/workflow/residual_analysis.h"
#include "cli/commands.h"
#include "cli/estimator_options.h"
#include "cli/fit_plot.h"
#include "cli/gnuplot.h"
#include "cli/output_file.h"
#include "cli/output_paths.h"
#include "cli/structure_options.h"

namespace ident::cli {
namespace {

constexpr long kInMemoryRows = 1'000'000;
constexpr int kResidualLags = 20;

struct FitCommandOptions {
  std::string data;
  StructureCliOptions structure;
  EstimatorCliOptions estimator;
  double split = 0.5;
  int passes = 1;
  std::string detrend;
  bool missing = false;
  bool json = false;
  std::string trace;
  std::string plot;
};

nlohmann::ordered_json RestartEventsJson(const std::vector<RestartEvent>& events) {
  nlohmann::ordered_json list = nlohmann::ordered_json::array();
  for (const RestartEvent& e : events)
    list.push_back({{"update", e.update},
                    {"replayed", e.replayed},
                    {"dropped", e.dropped},
                    {"low_weight_before", e.low_weight_before},
                    {"low_weight_after", e.low_weight_after},
                    {"resolved", e.resolved}});
  return list;
}

nlohmann::ordered_json ToJson(const workflow::FitResult& r, const std::string& data, double split,
                              const std::string& detrend) {
  auto number = [](double v) { return std::isfinite(v) ? nlohmann::ordered_json(v) : nlohmann::ordered_json(); };
  nlohmann::ordered_json j;
  j["data"] = data;
  j["estimator"] = r.estimator;
  j["kind"] = r.kind;
  j["passes"] = r.passes;
  j["structure"] = r.structure;
  j["parameter_names"] = r.parameter_names;
  j["theta"] = std::vector<double>(r.theta.data(), r.theta.data() + r.theta.size());
  auto& std_dev = j["theta_std"] = nlohmann::ordered_json::array();
  for (double v : r.theta_std) std_dev.push_back(number(v));
  j["noise_std"] = number(r.noise_std);
  j["fit_percent"] = {{"one_step", r.validation.one_step},
                      {"simulation", r.validation.simulation ? nlohmann::ordered_json(*r.validation.simulation)
                                                             : nlohmann::ordered_json()}};
  j["rms"] = {{"one_step", r.validation.rms_one_step},
              {"simulation", r.validation.rms_simulation ? nlohmann::ordered_json(*r.validation.rms_simulation)
                                                         : nlohmann::ordered_json()}};
  j["samples_estimation"] = r.samples_estimation;
  j["samples_validation"] = r.samples_validation;
  j["updates"] = r.updates;
  j["rejected"] = r.rejected;
  j["cleaned"] = r.cleaned;
  // The robust estimators' lock-in safeguard (null for RLS and with --exact).
  if (r.lock_in)
    j["lock_in"] = {{"window", r.lock_in->window},
                    {"threshold", r.lock_in->threshold},
                    {"restart", r.lock_in->restart},
                    {"flagged", r.lock_in->flagged},
                    {"restarts", r.lock_in->restarts},
                    {"low_weight_fraction", r.lock_in->low_weight_fraction},
                    {"events", RestartEventsJson(r.lock_in->events)},
                    {"start_update", r.lock_in->start_update},
                    {"start_window", r.lock_in->start_window},
                    {"start_at_end", r.lock_in->start_at_end}};
  else
    j["lock_in"] = nullptr;
  j["nu"] = r.nu;
  j["Dy"] = r.Dy;
  j["split"] = split;
  j["detrend"] = detrend;
  return j;
}

void PrintResiduals(const workflow::ResidualAnalysis& a) {
  auto worst = [](const std::vector<double>& r, int first_lag) {
    std::size_t k = 0;
    for (std::size_t i = 1; i < r.size(); ++i)
      if (std::abs(r[i]) > std::abs(r[k])) k = i;
    return std::make_pair(r[k], static_cast<int>(k) + first_lag);
  };
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

nlohmann::ordered_json ResidualJson(const workflow::ResidualAnalysis& a) {
  nlohmann::ordered_json j;
  j["samples"] = a.samples;
  j["band"] = a.band;
  j["autocorrelation"] = a.autocorrelation;
  auto& cross = j["cross_correlation"] = nlohmann::ordered_json::object();
  for (std::size_t i = 0; i < a.input_names.size(); ++i) cross[a.input_names[i]] = a.cross_correlation[i];
  j["q_auto"] = a.QAuto();
  j["q_auto_limit"] = a.QAutoLimit();
  j["white"] = a.White();
  j["independent"] = a.Independent();
  return j;
}

void PrintReport(const workflow::FitResult& r, const std::string& data, const FitCommandOptions& o) {
  fmt::print("{}: {} fitted by {} ({}{}, {} detrending)\n", data, r.structure, r.estimator, r.kind,
             r.passes > 1 ? fmt::format(", {} passes", r.passes) : "", o.detrend);
  if (o.split == 1)
    fmt::print("estimation and validation on all {} rows ({} updates", r.samples_estimation, r.updates);
  else
    fmt::print("estimation rows 1-{} ({} updates", r.samples_estimation, r.updates);
  if (r.rejected) fmt::print(", {} samples rejected as missing/invalid", r.rejected);
  if (r.cleaned) fmt::print(", {} outputs cleaned in later regressors", r.cleaned);
  fmt::print(")");
  if (o.split != 1)
    fmt::print(", validation rows {}-{}", r.samples_estimation + 1, r.samples_estimation + r.samples_validation);
  fmt::print("\n\n  {:<12} {:>14} {:>12}\n", "parameter", "estimate", "std");
  for (int i = 0; i < r.theta.size(); ++i)
    fmt::print("  {:<12} {:>14.6g} {:>12.4g}\n", r.parameter_names[i], r.theta(i), r.theta_std(i));
  fmt::print("\n  noise std {:.4g}\n", r.noise_std);
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
      fmt::print("    restart at update {}: replayed all {} samples kept{}; low weights {:.0f} % -> {:.0f} %{}\n",
                 e.update, e.replayed,
                 e.dropped ? fmt::format(" ({} older ones beyond the history limit dropped)", e.dropped) : "",
                 100 * e.low_weight_before, 100 * e.low_weight_after,
                 e.resolved ? "" : " (not a lock-in: the noise is heavier-tailed than the model; next restart waits)");
  }
  // Fit % is undefined (0/0) when the validation output is constant; the JSON has null there.
  auto percent = [](double p) { return std::isfinite(p) ? fmt::format("{:.2f} %", p) : std::string("undefined"); };
  fmt::print("  validation fit: one-step {} (RMS {:.4g})", percent(r.validation.one_step), r.validation.rms_one_step);
  if (r.validation.simulation)
    fmt::print(", simulation {} (RMS {:.4g})", percent(*r.validation.simulation), *r.validation.rms_simulation);
  fmt::print("\n");
}

void RunFit(const FitCommandOptions& o) {
  const std::string path = ResolveDataPath(o.data);
  CheckOutputPaths({{"--trace", o.trace}, {"--plot", o.plot}},
                   {{"input data file", path}, {"--prior file", o.estimator.prior_file}});
  if (!o.plot.empty()) CheckPlotFileName(o.plot);
  const io::CsvOptions csv{.missing_as_nan = o.missing};
  std::unique_ptr<workflow::DataSource> source = o.structure.MakeSource(io::CsvReader(path, csv).names(), path);
  // The record's length first: building an estimator costs O(rho^3) for large orders.
  workflow::FitOptions length_check;
  length_check.split = o.split;
  const int estimation_rows = workflow::CheckCsvRecordLength(path, csv, *source, length_check);
  const int rho = source->num_parameters();
  EstimatorSettings settings = o.estimator.Resolve(rho, "", estimation_rows);
  std::unique_ptr<AnyRegressionEstimator> estimator = MakeRegressionEstimator(settings, rho);  // checks the options
  workflow::FitOptions options;
  options.split = o.split;
  options.passes = o.passes;
  options.detrend = o.detrend == "none" ? workflow::Detrend::kNone : workflow::Detrend::kMean;
  options.decision = o.structure.Decision();
  if (settings.prior) options.min_regressor_information = 0;  // the user's prior, the user's scale
  // Default priors in the data's own scale, so that a record in small or large units fits as it does in
  // units of 1: RLS gets the flat prior of RegressionPrior::Flat(mean squares) (unless --exact, which keeps
  // the absolute flat prior of the recursion and with it the small-information check); the Kárný–Hangos
  // estimators' data-driven start-up prior is scale-invariant already (ident/regression/student_regression.h).
  const bool default_prior = !settings.prior && !settings.exact;
  const bool scaled_prior = default_prior && RegressionEstimatorTraits(settings.name).data_scaled_prior;
  if (default_prior && !scaled_prior) options.min_regressor_information = 0;
  auto use_scaled_prior = [&](const Eigen::VectorXd& mean_squares) {
    const std::optional<RegressionPrior> prior = DataScaledDefaultPrior(settings, mean_squares);
    if (!prior) return;  // out of range (or no usable sample): the absolute flat prior, whose check names the problem
    settings.prior = prior;
    estimator = MakeRegressionEstimator(settings, rho);
    options.min_regressor_information = 0;
  };
  // The trace and the plot go to temporary files, renamed onto their names only after the whole fit has
  // succeeded (cli/output_file.h): a fit that fails, e.g. on a bad row late in a streamed record, leaves
  // every existing file as it is. The report is printed after the renames, so a failed write leaves
  // stdout empty.
  std::optional<OutputFile> trace, plot;
  if (!o.trace.empty()) {
    trace.emplace(o.trace, "--trace file");
    options.trace = trace->stream();
  }
  if (!o.plot.empty()) plot.emplace(o.plot, "--plot file");
  auto commit_outputs = [&] {
    for (std::optional<OutputFile>* f : {&trace, &plot})
      if (*f) (*f)->Close();
    for (std::optional<OutputFile>* f : {&trace, &plot})
      if (*f) (*f)->Commit();
  };
  // Records up to kInMemoryRows rows are read whole, for the residual analysis and plots; longer ones
  // stream through the estimator in constant memory (without the residual analysis).
  if (o.plot.empty() && workflow::CountCsvDataRows(path) > kInMemoryRows) {
    if (scaled_prior) use_scaled_prior(workflow::CsvEstimationMeanSquares(path, csv, *source, options));
    const workflow::FitResult result = workflow::FitCsvFile(path, csv, *source, *estimator, options);
    commit_outputs();
    if (o.json) {
      nlohmann::ordered_json j = ToJson(result, path, o.split, o.detrend);
      j["residual_analysis"] = nlohmann::ordered_json();
      std::cout << j.dump(2) << "\n";
    } else {
      PrintReport(result, path, o);
      fmt::print("\n  residual analysis: skipped (record of more than {} rows, streamed)\n", kInMemoryRows);
    }
    return;
  }
  io::DataTable table = io::ReadCsv(path, csv);
  ParameterHistory history;
  if (!o.plot.empty()) {
    history.theta.resize(static_cast<std::size_t>(source->num_parameters()));
    options.on_update = [&history](int row, const AnyRegressionEstimator& e) {
      history.t.push_back(row + 1);
      const Eigen::VectorXd theta = e.parameters();
      for (int i = 0; i < theta.size(); ++i) history.theta[static_cast<std::size_t>(i)].push_back(theta(i));
    };
  }
  // The split and detrended table, for the prior's scale and the residual analysis on the validation part.
  io::DataTable prepared = table;
  const auto [estimation, validation] = workflow::PrepareData(prepared, *source, options);
  if (scaled_prior) use_scaled_prior(workflow::EstimationMeanSquares(prepared, estimation, *source));
  const workflow::FitResult result = workflow::Fit(std::move(table), *source, *estimator, options);
  std::optional<workflow::ResidualAnalysis> residuals;
  if (validation.count - source->first_regression_index() > kResidualLags + 1)
    residuals = workflow::AnalyseResiduals(prepared, validation, *source, result.theta, kResidualLags);
  if (plot) PlotFit(*plot, prepared, validation, *source, result.theta, history);
  commit_outputs();
  if (o.json) {
    nlohmann::ordered_json j = ToJson(result, path, o.split, o.detrend);
    j["residual_analysis"] = residuals ? ResidualJson(*residuals) : nlohmann::ordered_json();
    std::cout << j.dump(2) << "\n";
  } else {
    PrintReport(result, path, o);
    if (residuals) PrintResiduals(*residuals);
  }
}

}  // namespace

void AddFitCommand(CLI::App& app) {
  auto o = std::make_shared<FitCommandOptions>();
  CLI::App* fit = app.add_subcommand("fit", "Fit a model to recorded data with a recursive estimator");
  fit->add_option("DATA", o->data, "CSV file with a header, or a bundled dataset's name (e.g. dryer)")->required();
  o->structure.AddTo(*fit);
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
  fit->add_flag("--missing", o->missing, "Treat empty/NaN/Inf cells as missing samples instead of errors");
  fit->add_option("--trace", o->trace, "Write one CSV row per update: t,nu,beta,pred_err,theta1..,Dy");
  fit->add_option("--plot", o->plot,
                  "Draw measured vs one-step and simulated output (validation) and the parameter trajectories "
                  "into FILE.svg or FILE.png (needs gnuplot)");
  fit->add_flag("--json", o->json, "Print one JSON object instead of the report");
  fit->callback([o] {
    if (o->detrend.empty()) o->detrend = o->structure.intercept ? "none" : "mean";
    RunFit(*o);
  });
}

}  // namespace ident::cli
