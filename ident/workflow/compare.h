// `ident compare` as a library: seeded outlier injection and the scoring of several estimators on
// the same corrupted record.
//
// Protocol: split and detrend as `ident fit` (ident/workflow/fit.h). A clean least-squares
// fit (RLS with the flat prior = batch LS) on the estimation part gives θ_LS and the residual std σ.
// Each trial adds ±SIZE·σ (random sign) to y at ⌊RATE·N_est + ½⌋ distinct estimation rows drawn with
// seed SEED + trial, runs every estimator on that corrupted estimation part — detrended as `ident fit` detrends
// it for that estimator: the output's offset is the corrupted record's mean, or its Hampel-filtered mean for a
// robust estimator (FitOptions::robust_offset) — and scores the model, θ with that offset, on the
// untouched (uncorrupted) validation rows — with split = 1 the clean estimation rows themselves: fit % one-step and
// simulation, θ distance ‖θ̂ − θ_LS‖₂/‖θ_LS‖₂, and time per update (the recorded update sequence replayed on a fresh
// estimator in 7 timed blocks of at least 1 ms; the median of the blocks, then the median over the first 5 trials).
//
// Example:
//   OutlierSpec spec = OutlierSpec::Parse("0.05:20:1");
//   CompareResult r = Compare(table, *source, {ParseEstimatorSpec("rls")}, {.outliers = spec});
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "ident/io/csv.h"
#include "ident/registry/estimator_registry.h"
#include "ident/workflow/experiments.h"
#include "ident/workflow/fit.h"

namespace ident::workflow {

struct OutlierSpec {
  double rate = 0.05;  // fraction of estimation samples, in [0, 1)
  double size = 20;    // in units of the clean LS residual std, >= 0
  std::uint64_t seed = 1;
  // "RATE:SIZE[:SEED]" (e.g. "0.05:20", "0.1:10:7") or "none". Throws InvalidArgument naming --outliers.
  static OutlierSpec Parse(const std::string& text);
  std::string ToString() const;  // "0.05:20:1"
};

// Adds ±amplitude (random sign) to y(first + i) for ⌊rate·count + ½⌋ distinct i in [0, count), chosen
// by a partial Fisher–Yates shuffle driven by std::mt19937_64(seed) (index = draw mod m, sign = next
// draw's lowest bit), so the rows are the same on every platform. Returns the rows, ascending.
// Throws InvalidArgument for rate ∉ [0, 1), a negative or non-finite amplitude, or a bad segment.
std::vector<int> InjectOutliers(Eigen::Ref<Eigen::VectorXd> y, Segment segment, double rate, double amplitude,
                                std::uint64_t seed);

// Mean, standard deviation (n − 1; 0 for one value), min, median, 90th percentile (linear interpolation
// between order statistics, as numpy's default), max of a sample.
struct Spread {
  double mean = 0, std = 0, min = 0, median = 0, p90 = 0, max = 0;
  static Spread Of(std::vector<double> values);
};

struct CompareOptions {
  FitOptions fit;  // split, detrend, outlier decision for regressor cleaning, passes
  OutlierSpec outliers;
  int trials = 1;
  // Threads the trials are spread over (1: this thread only). The result is the same for any number: each
  // trial is seeded by its index and the trials are summed in order; the timed replays run afterwards,
  // one at a time.
  int jobs = 1;
  // Called after each (trial, estimator) run with (done, total), from the thread that made the run (one
  // call at a time).
  std::function<void(int, int)> progress;
};

struct EstimatorScore {
  std::string estimator;  // as given ("student:3")
  std::string kind;       // "recursive" or "batch"
  int passes = 1;         // passes over the estimation part that ran (FitOptions::passes)
  Eigen::VectorXd theta;  // mean over trials
  Spread one_step, simulation, theta_distance;
  std::vector<double> one_step_per_trial;        // NaN for a failed trial
  std::vector<double> theta_distance_per_trial;  // NaN for a failed trial
  bool has_simulation = false;
  double ns_per_update = 0;  // median over the first 5 trials of each one's median timed replay
  double cleaned = 0;        // mean number of outputs cleaned in the regressors
  // The output's detrending offset subtracted for this estimator (mean over trials; data units; 0 without
  // detrending): the model is θ around it.
  double output_offset = 0;
  int failed_trials = 0;  // trials whose estimate failed or was unusable (left out of the spreads)
  std::string failure;    // the first such trial's reason, "" if none
};

struct CompareResult {
  std::string structure;
  std::vector<std::string> parameter_names;
  Segment estimation, validation;
  Eigen::VectorXd theta_ls;  // clean-data least squares
  double sigma = 0;          // its residual std (the outlier unit)
  double output_mean = 0;    // the clean record's detrending mean of the output (0 without detrending)
  FitScores reference;       // its validation scores
  int outliers_per_trial = 0;
  std::vector<EstimatorScore> scores;  // sorted by mean one-step fit, best first
  // The record's experiments (TableExperiments of the compared table; callers that know better names set
  // them) and its time column (workflow/time_column.h; null when not checked).
  std::vector<Experiment> experiments;
  std::optional<TimeCheck> time;
};

// Throws InvalidArgument for bad options (including an unknown estimator, before any run starts).
CompareResult Compare(io::DataTable data, DataSource& source, const std::vector<EstimatorSettings>& estimators,
                      const std::vector<std::string>& labels, const CompareOptions& options);

}  // namespace ident::workflow
