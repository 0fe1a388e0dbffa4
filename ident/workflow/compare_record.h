// Comparing estimators on a record from a request as a user states it: the steps `ident compare` and the
// Python package's `ident.compare` share, and the JSON object of `ident compare --json`.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "ident/io/csv.h"
#include "ident/workflow/compare.h"
#include "ident/workflow/estimator_spec.h"
#include "ident/workflow/model_spec.h"

namespace ident::workflow {

struct CompareRequest {
  ModelSpec model;
  EstimatorSpec options;  // the options every compared estimator shares (its `estimator` is not used)
  std::vector<std::string> estimators{"rls", "cauchy", "student:3"};
  OutlierSpec outliers;
  int trials = 1;
  int jobs = 1;  // threads for the trials (CompareOptions::jobs); the result does not depend on it
  int passes = 1;
  double split = 0.5;
  std::string detrend;  // "mean" | "none"; empty: model.DefaultDetrend()
  std::function<void(int, int)> progress;

  std::string ResolvedDetrend() const { return detrend.empty() ? model.DefaultDetrend() : detrend; }
};

// `name` is the record's name in messages. Throws InvalidArgument for bad options (before any run).
CompareResult CompareRecord(io::DataTable table, const std::string& name, const CompareRequest& request);

// The JSON object of `ident compare --json`: data, structure, parameter_names, estimation_rows,
// validation_rows, outliers, trials, clean_regressors, reference, estimators, experiments ([{name, rows}]),
// time_gaps (null when no time column was checked). Non-finite numbers are null.
nlohmann::ordered_json CompareJson(const CompareResult& result, const std::string& data, const OutlierSpec& outliers,
                                   int trials, const std::string& clean_regressors);

}  // namespace ident::workflow
