// Fitting a record from a request as a user states it (model, estimator, split, passes, detrending):
// the steps `ident fit` and the Python package's `ident.fit` share.
//
//   PlanFit     resolves the estimator options and builds the estimator (before any data is read: a bad
//               option fails first); says whether its default prior is to be put in the data's scale
//   FitTable    splits and detrends a table in memory, scales the default prior, estimates, scores, and
//               analyses the validation residuals
//   FitRecord   both, from a table and a request
//   FitJson     the result as the JSON object of `ident fit --json`
//
// Default priors are in the data's own scale, so that a record in small or large units fits as it does
// in units of 1: RLS gets RegressionPrior::Flat(mean squares of the estimation part) unless `exact`, which
// keeps the absolute flat prior of the recursion and with it the small-information check; the
// Kárný–Hangos estimators' data-driven start-up prior is scale-invariant already.
#pragma once

#include <memory>
#include <optional>
#include <string>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "ident/io/csv.h"
#include "ident/workflow/estimator_spec.h"
#include "ident/workflow/experiments.h"
#include "ident/workflow/fit.h"
#include "ident/workflow/model_spec.h"
#include "ident/workflow/residual_analysis.h"

namespace ident::workflow {

struct FitRequest {
  ModelSpec model;
  EstimatorSpec estimator;
  double split = 0.5;
  int passes = 1;
  std::string detrend;     // "mean" | "none"; empty: model.DefaultDetrend()
  int residual_lags = 20;  // lags of the residual analysis; 0: none

  std::string ResolvedDetrend() const { return detrend.empty() ? model.DefaultDetrend() : detrend; }
};

struct FitPlan {
  EstimatorSettings settings;
  std::unique_ptr<AnyRegressionEstimator> estimator;
  FitOptions options;         // split, passes, detrending, decision; trace and on_update are the caller's
  bool scaled_prior = false;  // the default prior is to be put in the data's scale (UseScaledPrior)

  // Rebuilds the estimator with its default prior in the data's scale (UseDataScaledPrior, from the mean
  // squares of y and the regressors over the estimation part); keeps the absolute default (whose check then
  // names the problem) when the mean squares are out of range or no sample is usable.
  void UseScaledPrior(const Eigen::VectorXd& mean_squares);
};

// Throws InvalidArgument / DataError naming the option.
FitPlan PlanFit(const FitRequest& request, int num_parameters, long estimation_rows);
// PlanFit's options and settings without the estimator (null) and without the checks that need the record's
// length: what a streamed fit's first pass (ScanCsvFirstPass) needs to know before the record is counted.
FitPlan PlanFitOptions(const FitRequest& request, int num_parameters);

struct RecordFit {
  FitResult result;
  io::DataTable prepared;  // the split and detrended table
  Segment estimation, validation;
  std::vector<std::pair<std::string, double>> detrend_means;  // (column, mean subtracted); empty: none
  // The experiments of the table (ident/workflow/experiments.h), named "1", "2", … from its
  // experiment_starts (callers that know better names set them).
  std::vector<Experiment> experiments;
  // When residual_lags > 0 and the validation part has more than residual_lags + 1 samples.
  std::optional<ResidualAnalysis> residuals;
};

// In memory. `plan.options.on_update` and `.trace`, if set, see every update.
RecordFit FitTable(io::DataTable table, DataSource& source, FitPlan& plan, int residual_lags = 20);

// FitTable's fit of a CSV file, streamed (FitCsvFile of fit.h) with `layout` from CheckCsvLayout: the
// detrending means are computed once for the data-scaled prior (plan.scaled_prior) and the fit. `filled`:
// the time gaps CheckCsvLayout filled (the same object), whose missing rows every pass reads.
FitResult FitCsvFile(const std::string& path, const io::CsvOptions& csv, DataSource& source, FitPlan& plan,
                     const CsvLayout& layout, const TimeCheck* filled = nullptr);

// The same with the layout and detrending offsets of ScanCsvFirstPass (fit.h), made with plan.options (as
// PlanFitOptions gives them): no pass of its own for the means.
FitResult FitCsvFile(const std::string& path, const io::CsvOptions& csv, DataSource& source, FitPlan& plan,
                     const CsvFirstPass& first);

// `name` is the record's name in messages (a path, "DataFrame", …).
RecordFit FitRecord(io::DataTable table, const std::string& name, const FitRequest& request);

// The rows of the estimation part for a split (0 for a split ∉ (0, 1], which Fit refuses by name).
long EstimationRows(long rows, double split);

// The means a fit subtracted, by column name (empty without detrending).
inline const std::vector<std::pair<std::string, double>>& DetrendMeans(const RecordFit& fit) {
  return fit.detrend_means;
}

// Validates the fit on a separate record instead of its own validation part (`ident fit --validate`): the
// record's columns minus the fit's detrending means, scored from its first row as a segment of its own,
// with the residual analysis as FitTable makes it. `name` names the record (FitResult::validation_data).
void ValidateOn(RecordFit& fit, io::DataTable record, const std::string& name, const ModelSpec& model,
                int residual_lags = 20);

// The JSON object of `ident fit --json`: data, estimator, kind, passes, structure, parameter_names, theta,
// theta_std, noise_std, fit_percent, rms, simulation_diverged_at, samples_estimation, samples_validation,
// updates, rejected, cleaned, lock_in, nu, Dy, split, detrend, time_gaps ([{row, t_before, t_after, missing,
// filled}]; null when no time column was checked, workflow/time_column.h), detrend_means ({column: mean}; null when
// `means` is null, as for a streamed record), residual_analysis (null when not computed), experiments
// ([{name, rows: [first, last]}], 1-based rows of the fitted table; null when `experiments` is null).
// Non-finite numbers are null.
nlohmann::ordered_json FitJson(const FitResult& result, const std::string& data, double split,
                               const std::string& detrend, const ResidualAnalysis* residuals,
                               const std::vector<std::pair<std::string, double>>* means,
                               const std::vector<Experiment>* experiments = nullptr);

}  // namespace ident::workflow
