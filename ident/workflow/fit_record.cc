#include "ident/workflow/fit_record.h"

#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "common/error.h"
#include "ident/workflow/json_number.h"

namespace ident::workflow {
namespace {

nlohmann::ordered_json RestartEventsJson(const std::vector<RestartEvent>& events) {
  nlohmann::ordered_json list = nlohmann::ordered_json::array();
  for (const RestartEvent& e : events)
    list.push_back({{"update", e.update},
                    {"replayed", e.replayed},
                    {"dropped", e.dropped},
                    {"left_out", e.left_out},
                    {"low_weight_before", e.low_weight_before},
                    {"low_weight_after", e.low_weight_after},
                    {"resolved", e.resolved},
                    {"end_of_data", e.end_of_data},
                    {"pass", e.pass}});
  return list;
}

nlohmann::ordered_json FitJsonWithoutResiduals(const FitResult& r, const std::string& data, double split,
                                               const std::string& detrend) {
  nlohmann::ordered_json j;
  j["data"] = data;
  j["estimator"] = r.estimator;
  j["kind"] = r.kind;
  j["passes"] = r.passes;
  j["structure"] = r.structure;
  j["parameter_names"] = r.parameter_names;
  j["theta"] = std::vector<double>(r.theta.data(), r.theta.data() + r.theta.size());
  auto& std_dev = j["theta_std"] = nlohmann::ordered_json::array();
  for (double v : r.theta_std) std_dev.push_back(FiniteOrNull(v));
  j["noise_std"] = FiniteOrNull(r.noise_std);
  j["fit_percent"] = {{"one_step", r.validation.one_step},
                      {"simulation", r.validation.simulation ? nlohmann::ordered_json(*r.validation.simulation)
                                                             : nlohmann::ordered_json()}};
  j["rms"] = {{"one_step", r.validation.rms_one_step},
              {"simulation", r.validation.rms_simulation ? nlohmann::ordered_json(*r.validation.rms_simulation)
                                                         : nlohmann::ordered_json()}};
  j["simulation_diverged_at"] =
      r.validation.simulation_diverged_at ? nlohmann::ordered_json(*r.validation.simulation_diverged_at) : nullptr;
  j["samples_estimation"] = r.samples_estimation;
  j["samples_validation"] = r.samples_validation;
  j["validation_data"] =
      r.validation_data.empty() ? nlohmann::ordered_json() : nlohmann::ordered_json(r.validation_data);
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
  j["time_gaps"] = TimeGapsJson(r.time);
  return j;
}

nlohmann::ordered_json ResidualJson(const ResidualAnalysis& a) {
  nlohmann::ordered_json j;
  j["samples"] = a.samples;
  j["band"] = a.band;
  j["applies"] = a.applies;
  if (!a.applies) {  // a static regression: no correlations over lags (residual_analysis.h)
    for (const char* key : {"autocorrelation", "cross_correlation", "q_auto", "q_auto_limit", "white", "independent"})
      j[key] = nullptr;
    return j;
  }
  j["autocorrelation"] = a.autocorrelation;
  auto& cross = j["cross_correlation"] = nlohmann::ordered_json::object();
  for (std::size_t i = 0; i < a.input_names.size(); ++i) cross[a.input_names[i]] = a.cross_correlation[i];
  j["q_auto"] = a.QAuto();
  j["q_auto_limit"] = a.QAutoLimit();
  j["white"] = a.White();
  j["independent"] = a.Independent();
  return j;
}

}  // namespace

void FitPlan::UseScaledPrior(const Eigen::VectorXd& mean_squares) {
  // Out of range (or no usable sample): the absolute default prior, whose check names the problem.
  if (!UseDataScaledPrior(settings, mean_squares)) return;
  estimator = MakeRegressionEstimator(settings, estimator->num_parameters());
  options.min_regressor_information = 0;
}

long EstimationRows(long rows, double split) {
  const bool valid_split = std::isfinite(split) && split > 0 && split <= 1;
  return !valid_split ? 0 : split == 1 ? rows : static_cast<long>(std::floor(split * static_cast<double>(rows)));
}

namespace {

// PlanFit's options, from its resolved settings.
void SetPlanOptions(FitPlan& plan, const FitRequest& request) {
  const std::string detrend = request.ResolvedDetrend();
  IDENT_REQUIRE(detrend == "mean" || detrend == "none", "--detrend '{}': need mean or none", detrend);
  plan.options.split = request.split;
  plan.options.passes = request.passes;
  plan.options.detrend = detrend == "none" ? Detrend::kNone : Detrend::kMean;
  plan.options.robust_offset = RegressionEstimatorTraits(plan.settings.name).robust;
  plan.options.decision = request.model.Decision();
  if (plan.settings.prior) plan.options.min_regressor_information = 0;  // the user's prior, the user's scale
  const bool default_prior = !plan.settings.prior && !plan.settings.exact;
  const EstimatorTraits traits = RegressionEstimatorTraits(plan.settings.name);
  plan.scaled_prior = default_prior && traits.data_scaled_prior;
  // The regressor-information check guards the flat prior; a Kárný–Hangos start is scale-invariant.
  if (default_prior && (!plan.scaled_prior || traits.lock_in)) plan.options.min_regressor_information = 0;
}

}  // namespace

FitPlan PlanFit(const FitRequest& request, int num_parameters, long estimation_rows) {
  FitPlan plan;
  plan.settings = request.estimator.Resolve(num_parameters, "", estimation_rows);
  plan.estimator = MakeRegressionEstimator(plan.settings, num_parameters);  // checks the options
  SetPlanOptions(plan, request);
  return plan;
}

FitPlan PlanFitOptions(const FitRequest& request, int num_parameters) {
  FitPlan plan;
  plan.settings = request.estimator.Resolve(num_parameters, "", 0);
  SetPlanOptions(plan, request);
  return plan;
}

RecordFit FitTable(io::DataTable table, DataSource& source, FitPlan& plan, int residual_lags) {
  RecordFit fit;
  fit.experiments = TableExperiments(table);
  fit.prepared = std::move(table);
  std::vector<std::pair<int, double>> means;
  std::tie(fit.estimation, fit.validation) = PrepareData(fit.prepared, source, plan.options, &means);
  for (const auto& [column, mean] : means)
    fit.detrend_means.emplace_back(fit.prepared.names[static_cast<std::size_t>(column)], mean);
  if (plan.scaled_prior) plan.UseScaledPrior(EstimationMeanSquares(fit.prepared, fit.estimation, source));
  fit.result = FitPrepared(fit.prepared, fit.estimation, fit.validation, source, *plan.estimator, plan.options);
  if (residual_lags > 0 && fit.validation.count - source.first_regression_index() > residual_lags + 1)
    fit.residuals = AnalyseResiduals(fit.prepared, fit.validation, source, fit.result.theta, residual_lags);
  return fit;
}

RecordFit FitRecord(io::DataTable table, const std::string& name, const FitRequest& request) {
  std::unique_ptr<DataSource> source = request.model.MakeSource(table.names, name);
  FitPlan plan = PlanFit(request, source->num_parameters(), EstimationRows(table.num_rows(), request.split));
  return FitTable(std::move(table), *source, plan, request.residual_lags);
}

void ValidateOn(RecordFit& fit, io::DataTable record, const std::string& name, const ModelSpec& model,
                int residual_lags) {
  std::unique_ptr<DataSource> source = model.MakeSource(record.names, name);
  for (const auto& [column, mean] : fit.detrend_means) record.values.col(record.ColumnIndex(column)).array() -= mean;
  const Segment all{0, record.num_rows()};
  IDENT_REQUIRE(all.count > source->first_regression_index() + 1,
                "{}: {} rows are too few to validate {} (the first {} have no regressor)", name, all.count,
                source->structure(), source->first_regression_index());
  fit.result.validation = Score(record, all, *source, fit.result.theta);
  fit.result.samples_validation = all.count;
  fit.result.validation_data = name;
  fit.residuals.reset();
  if (residual_lags > 0 && all.count - source->first_regression_index() > residual_lags + 1)
    fit.residuals = AnalyseResiduals(record, all, *source, fit.result.theta, residual_lags);
  fit.prepared = std::move(record);
  fit.validation = all;
}

nlohmann::ordered_json FitJson(const FitResult& result, const std::string& data, double split,
                               const std::string& detrend, const ResidualAnalysis* residuals,
                               const std::vector<std::pair<std::string, double>>* means,
                               const std::vector<Experiment>* experiments) {
  nlohmann::ordered_json j = FitJsonWithoutResiduals(result, data, split, detrend);
  if (means) {
    auto& object = j["detrend_means"] = nlohmann::ordered_json::object();
    for (const auto& [name, mean] : *means) object[name] = mean;
  } else {
    j["detrend_means"] = nullptr;
  }
  j["residual_analysis"] = residuals ? ResidualJson(*residuals) : nlohmann::ordered_json();
  j["experiments"] = experiments ? ExperimentsJson(*experiments) : nlohmann::ordered_json();
  return j;
}

}  // namespace ident::workflow
