#include "ident/workflow/compare_record.h"

#include <cmath>
#include <memory>
#include <utility>

#include "common/error.h"
#include "ident/workflow/fit_record.h"
#include "ident/workflow/json_number.h"

namespace ident::workflow {
namespace {

nlohmann::ordered_json SpreadJson(const Spread& s) {
  return {{"mean", FiniteOrNull(s.mean)},     {"std", FiniteOrNull(s.std)}, {"min", FiniteOrNull(s.min)},
          {"median", FiniteOrNull(s.median)}, {"p90", FiniteOrNull(s.p90)}, {"max", FiniteOrNull(s.max)}};
}

std::vector<double> ToStd(const Eigen::VectorXd& v) { return std::vector<double>(v.data(), v.data() + v.size()); }

}  // namespace

nlohmann::ordered_json CompareJson(const CompareResult& r, const std::string& path, const OutlierSpec& spec, int trials,
                                   const std::string& cleaning) {
  nlohmann::ordered_json j;
  j["data"] = path;
  j["structure"] = r.structure;
  j["parameter_names"] = r.parameter_names;
  j["estimation_rows"] = {r.estimation.first + 1, r.estimation.first + r.estimation.count};
  j["validation_rows"] = {r.validation.first + 1, r.validation.first + r.validation.count};
  j["outliers"] = {{"rate", spec.rate},
                   {"size", spec.size},
                   {"seed", spec.seed},
                   {"per_trial", r.outliers_per_trial},
                   {"sigma", r.sigma}};
  j["trials"] = trials;
  j["clean_regressors"] = cleaning;
  j["reference"] = {{"estimator", "clean-data least squares"},
                    {"theta", ToStd(r.theta_ls)},
                    {"fit_percent",
                     {{"one_step", r.reference.one_step},
                      {"simulation", r.reference.simulation ? FiniteOrNull(*r.reference.simulation) : nullptr}}}};
  auto& list = j["estimators"] = nlohmann::ordered_json::array();
  for (const EstimatorScore& s : r.scores) {
    nlohmann::ordered_json e;
    e["estimator"] = s.estimator;
    e["kind"] = s.kind;
    e["passes"] = s.passes;
    e["theta"] = ToStd(s.theta);
    e["fit_percent"] = {{"one_step", FiniteOrNull(s.one_step.mean)},
                        {"simulation", s.has_simulation ? FiniteOrNull(s.simulation.mean) : nullptr}};
    e["theta_distance"] = FiniteOrNull(s.theta_distance.mean);
    e["ns_per_update"] = s.ns_per_update;
    e["spread"] = {{"fit_one_step", SpreadJson(s.one_step)},
                   {"fit_simulation", s.has_simulation ? SpreadJson(s.simulation) : nullptr},
                   {"theta_distance", SpreadJson(s.theta_distance)}};
    e["cleaned_per_trial"] = FiniteOrNull(s.cleaned);
    e["output_offset"] = FiniteOrNull(s.output_offset);
    e["failed_trials"] = s.failed_trials;
    e["failure"] = s.failure.empty() ? nlohmann::ordered_json() : nlohmann::ordered_json(s.failure);
    list.push_back(std::move(e));
  }
  j["experiments"] = ExperimentsJson(r.experiments);
  j["time_gaps"] = TimeGapsJson(r.time);
  return j;
}

CompareResult CompareRecord(io::DataTable table, const std::string& name, const CompareRequest& request) {
  std::unique_ptr<DataSource> source = request.model.MakeSource(table.names, name);
  const std::vector<std::string> names = SplitEstimatorLists(request.estimators);
  const long estimation_rows = EstimationRows(table.num_rows(), request.split);
  const std::vector<EstimatorSettings> settings =
      request.options.ResolveAll(source->num_parameters(), names, estimation_rows);
  const std::string detrend = request.ResolvedDetrend();
  IDENT_REQUIRE(detrend == "mean" || detrend == "none", "--detrend '{}': need mean or none", detrend);
  CompareOptions options;
  options.fit.split = request.split;
  options.fit.passes = request.passes;
  options.fit.detrend = detrend == "none" ? Detrend::kNone : Detrend::kMean;
  options.fit.decision = request.model.Decision();
  options.outliers = request.outliers;
  options.trials = request.trials;
  options.jobs = request.jobs;
  options.progress = request.progress;
  return Compare(std::move(table), *source, settings, names, options);
}

}  // namespace ident::workflow
