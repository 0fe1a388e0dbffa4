// The steps of fitting a record that the in-memory and the streamed workflow share (internal to
// ident/workflow/; see ident/workflow/fit.h): the split, detrending means, recursive estimation with output
// cleaning and passes, scoring, the summary and its usability check, the mean squares for data-scaled priors.
#pragma once

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <fmt/format.h>
#include <Eigen/Core>

#include "common/dense_decompositions.h"
#include "common/error.h"
#include "ident/regression/rls.h"
#include "ident/workflow/fit.h"
#include "ident/workflow/spike_robust_mean.h"

namespace ident::workflow::internal {

// The estimation and validation segments of an n-row record; checks they are long enough.
inline std::pair<Segment, Segment> Split(int n, const DataSource& source, const FitOptions& options,
                                         const std::string& name) {
  IDENT_REQUIRE(std::isfinite(options.split) && options.split > 0 && options.split <= 1,
                "split = {}; need 0 < split <= 1", options.split);
  const int n_est = options.split == 1 ? n : static_cast<int>(std::floor(options.split * n));
  const Segment estimation{0, n_est};
  const Segment validation = options.split == 1 ? Segment{0, n} : Segment{n_est, n - n_est};
  const int t0 = source.first_regression_index();
  const int rho = source.num_parameters();
  IDENT_REQUIRE(estimation.count - t0 >= rho + 1,
                "{}: the estimation part has {} rows; {} with {} parameters needs at least {} (lower the orders or "
                "raise --split)",
                name, estimation.count, source.structure(), rho, t0 + rho + 1);
  IDENT_REQUIRE(validation.count - t0 >= 2, "{}: the validation part has {} rows; {} needs at least {} (lower --split)",
                name, validation.count, source.structure(), t0 + 2);
  return {estimation, validation};
}

// Mean of a column's non-missing values, m ← m + (v − m)/k: exact for a constant column even near
// 1e308, where a plain sum would overflow. 0 for a column with no values.
class RunningMean {
 public:
  void Add(double v) {
    if (std::isnan(v)) return;
    ++count_;
    mean_ += (v - mean_) / static_cast<double>(count_);
  }
  double Get(const std::string& source, const std::string& column) const {
    IDENT_REQUIRE(std::isfinite(mean_),
                  "{}: the mean of column '{}' overflows (values near 1e308 of both signs); rescale the data or "
                  "pass --detrend none",
                  source, column);
    return mean_;
  }

 private:
  long count_ = 0;
  double mean_ = 0;
};

// The column whose detrending offset is FitOptions::robust_offset's (the output of a dynamic structure,
// when both apply), or −1.
inline int RobustOffsetColumn(const FitOptions& options, const DataSource& source) {
  return options.detrend == Detrend::kMean && options.robust_offset && source.dynamic() ? source.output_column() : -1;
}

// FitOptions::robust_offset's offset of an output column (SpikeRobustMean), with RunningMean's check.
inline double RobustOffset(const Eigen::Ref<const Eigen::VectorXd>& y, const std::string& source,
                           const std::string& column) {
  const double m = SpikeRobustMean(y);
  IDENT_REQUIRE(std::isfinite(m),
                "{}: the mean of column '{}' overflows (values near 1e308 of both signs); rescale the data or "
                "pass --detrend none",
                source, column);
  return m;
}

// Recursive estimation, one row at a time (rows of one segment, in order).
class Estimation {
 public:
  Estimation(DataSource& source, AnyRegressionEstimator& estimator, const FitOptions& options)
      : source_(source),
        estimator_(estimator),
        trace_(options.trace),
        min_information_(options.min_regressor_information),
        decision_(options.decision),
        on_update_(options.on_update),
        on_row_(options.on_row),
        z_(source.num_parameters()),
        z_measured_(source.num_parameters()),
        ZtZ_(Eigen::MatrixXd::Zero(source.num_parameters(), source.num_parameters())),
        max_abs_(Eigen::VectorXd::Zero(source.num_parameters())),
        judged_(estimator.judges_outliers()),
        in_startup_(estimator.in_startup()),
        uses_estimate_(source.uses_estimate()),
        batch_(estimator.kind() == "batch") {
    source_.Reset();
    // ARMAX/OE/BJ: the first pass starts with no estimate (the caller clears it), a further pass from the
    // residuals of the pass before.
    // While a robust start-up collects its window the estimate stays the prior's, and residuals of the
    // prior (ε = v = y) would make the C and D columns copies of the output's: a least-squares shadow
    // estimate forms them until the start is made, with the measured y for the noise-free output (noise-free
    // outputs of a few samples' estimates would set the window's column scales and its robust fit).
    // A batch estimator solves on all its samples whenever it is read: the regressors take its estimate at
    // geometrically spaced updates (from 4ρ on, then 10 % more samples each time: O(N) solving in all) and keep
    // it in between; before the first, the least-squares shadow forms them.
    if (uses_estimate_ && (in_startup_ || batch_)) shadow_.emplace(source.num_parameters());
    next_batch_read_ = std::max(20, 4 * source.num_parameters());
  }

  // `r` is the 0-based row index in the record (the trace prints r + 1). Returns the estimator's step, or
  // nothing when no regression happens at this row (the regressor's first rows).
  std::optional<StepReport> Row(const Eigen::VectorXd& row, int r) {
    if (on_row_) on_row_(r);
    const double y = row(source_.output_column());
    bool flagged = false;
    double y_hat = std::nan(""), scale = std::nan("");
    std::optional<StepReport> step;
    if (source_.Regressor(row, z_)) {
      // y(t−1) was cleaned: keep the reading of it (additive outlier or innovation) that predicts y(t) better,
      // by the model's predictions, or by the warm-up screen's own predictor if the screen cleaned it (a
      // start-up's provisional estimate is no model: it would restore the outlier).
      if (source_.MeasuredRegressor(z_measured_) && KeepMeasured(y)) {
        source_.RestoreMeasured();
        z_ = z_measured_;
      }
      // A regressor that holds a cleaned output is left out, as if that output were missing: the cleaned
      // value is a prediction, and an equation built on it is an errors-in-variables one whose error, of
      // the size of the prediction error, biases the estimate where the model predicts poorly. Its
      // output is still judged (a gross error against the prediction is cleaned in turn).
      if (source_.RegressorHoldsCleaned()) {
        y_hat = estimator_.Predict(z_);
        if (judged_) scale = estimator_.noise_std();
        source_.PushCheckedOutput(y, y_hat, scale, /*flagged=*/judged_, judged_);
        StepReport skipped;
        skipped.status = StepStatus::kSkipped;
        skipped.prediction_error = y - y_hat;
        return skipped;
      }
      const double y_regressed = source_.RegressionOutput(y);  // y, or RPEM's linearised output
      const StepReport report = *(step = estimator_.Update(y_regressed, z_));
      if (in_startup_ && !estimator_.in_startup()) {  // the robust start is made: the model judges from now on
        in_startup_ = false;
        source_.EndCleaningWarmUp();
      }
      // RPLR: the a-posteriori residual ε(t) = y(t) − θ(t)'z(t) and w(t) enter later regressors.
      if (uses_estimate_ && !in_startup_ && !batch_) {
        source_.TrackEstimate(estimator_.parameters(), /*start_up=*/false);
      } else if (batch_ && uses_estimate_ && report.updated() && updates_ + 1 >= next_batch_read_) {
        source_.TrackEstimate(estimator_.parameters(), /*start_up=*/false);
        next_batch_read_ = std::max(next_batch_read_ + 1, static_cast<long>(1.1 * (updates_ + 1)));
        shadow_.reset();
      } else if (shadow_) {
        shadow_->Update(y_regressed, z_);
        source_.TrackEstimate(shadow_->parameters(), /*start_up=*/true);
      }
      flagged = decision_.Flags(report);
      // Every prediction ŷ goes to the cleaner (its gross-error test compares |y − ŷ| with the robust
      // scale of all recent prediction errors); a flagged output is rebuilt from ŷ and the noise scale.
      // An estimator that gives no verdicts has its outputs stored as measured: no scale is asked of it (a
      // batch estimator would solve all samples for it).
      y_hat = y - report.prediction_error;
      if (judged_) scale = estimator_.noise_std();
      if (report.updated()) {
        ++updates_;
        for (Eigen::Index j = 0; j < z_.size(); ++j) {  // Z'Z += zz' (lower) and max |z_i|: cheaper than Eigen's
          for (Eigen::Index i = j; i < z_.size(); ++i) ZtZ_(i, j) += z_(j) * z_(i);
          max_abs_(j) = std::max(max_abs_(j), std::abs(z_(j)));
        }
        if (on_update_) on_update_(r, report, estimator_);
        if (trace_) {
          const Eigen::VectorXd theta = estimator_.parameters();
          WriteTraceRow(trace_, {.t = r + 1,
                                 .nu = report.nu,
                                 .beta = report.weight,
                                 .pred_err = report.prediction_error,
                                 .theta = &theta,
                                 .Dy = estimator_.Dy()});
        }
      } else {
        ++rejected_;
        failed_ += report.status == StepStatus::kNumericalFailure;
      }
    }
    source_.PushCheckedOutput(y, y_hat, scale, flagged, judged_);
    return step;
  }

  // A further experiment starts at the next row: its regressors restart (DataSource::Restart); a cleaner
  // whose estimator has made its robust start judges by the model at once.
  void Restart() {
    source_.Restart();
    if (!in_startup_) source_.EndCleaningWarmUp();
  }

  // The end of the pass: a start-up that still waits starts from every sample seen. Identifiability:
  // every regressor must vary and none may be a combination of the others.
  std::pair<int, int> Finish(const std::string& name) {
    estimator_.FinishStartup();
    // A competing restart replays the kept regressors, which must not depend on the estimate.
    if (!uses_estimate_) estimator_.ReconsiderAtEnd();
    const int rho = source_.num_parameters();
    const std::vector<std::string> names = source_.parameter_names();
    IDENT_REQUIRE(updates_ > 0 || failed_ < rejected_,
                  "{}: every update of the estimation part ({} samples) was refused as numerically unsafe (values "
                  "extremely far from unit scale, e.g. near 1e100? rescale the data or give a prior; or a "
                  "forgetting factor far below 1, which discards nearly all information at each step?)",
                  name, rejected_);
    IDENT_REQUIRE(updates_ > 0,
                  "{}: none of the {} samples of the estimation part could be used (all missing, or too large: "
                  "squares beyond 1e308); rescale the data",
                  name, rejected_);
    const Eigen::MatrixXd G = ZtZ_.selfadjointView<Eigen::Lower>();
    const Eigen::VectorXd scale = G.diagonal().cwiseSqrt();
    for (int i = 0; i < rho; ++i)
      IDENT_REQUIRE(scale(i) > 0 || max_abs_(i) == 0,
                    "{}: regressor '{}' has sum of squares 0 over the estimation part: its values (largest {:.3g}) "
                    "are too small to square in double precision (values near 1e-200?); rescale the data",
                    name, names[i], max_abs_(i));
    for (int i = 0; i < rho; ++i)
      IDENT_REQUIRE(scale(i) > 0,
                    "{}: regressor '{}' is identically zero over the estimation part (a constant column "
                    "after detrending?); the model is not identifiable",
                    name, names[i]);
    for (int i = 0; i < rho; ++i)
      IDENT_REQUIRE(G(i, i) >= min_information_,
                    "{}: regressor '{}' has sum of squares {:.3g} over the estimation part, too small against the "
                    "default flat prior (values near 1e-150?); rescale the data or give a prior",
                    name, names[i], G(i, i));
    IDENT_REQUIRE(scale.allFinite(),
                  "{}: the regressors' sum of squares overflows (values near 1e308?); rescale the data", name);
    const Eigen::MatrixXd C = scale.cwiseInverse().asDiagonal() * G * scale.cwiseInverse().asDiagonal();
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig = dense::SymmetricEigen(C);
    IDENT_REQUIRE(eig.eigenvalues()(0) > 1e-12 * rho,
                  "{}: the regressors are collinear over the estimation part (smallest eigenvalue of their "
                  "correlation matrix {:.3g}); the model is not identifiable (if a gross outlier has moved the "
                  "detrending mean, try --detrend none)",
                  name, eig.eigenvalues()(0));
    return {updates_, rejected_};
  }

 private:
  bool KeepMeasured(double y) const {
    if (const std::optional<bool> nearer = source_.MeasuredIsNearer(y)) return *nearer;
    // An innovation outlier is carried on by the dynamics: with the cleaned reading y(t) is a gross error (the
    // echo was not predicted), with the measured one an ordinary one. Anything else keeps the cleaned reading:
    // two outliers in a row make the second look like an echo, and a model in which y(t−1) barely matters
    // cannot tell the readings apart, while a measured outlier restored in error is a leverage point.
    const double measured = y - estimator_.Predict(z_measured_), cleaned = y - estimator_.Predict(z_);
    return std::abs(measured) < std::abs(cleaned) && !source_.IsGrossError(measured) && source_.IsGrossError(cleaned);
  }

  DataSource& source_;
  AnyRegressionEstimator& estimator_;
  std::FILE* trace_;
  double min_information_;
  OutlierDecision decision_;
  std::function<void(int row, const StepReport& step, const AnyRegressionEstimator&)> on_update_;
  std::function<void(int row)> on_row_;
  Eigen::VectorXd z_, z_measured_;
  Eigen::MatrixXd ZtZ_;
  Eigen::VectorXd max_abs_;   // largest |z_i| over the updates (tells underflowing squares from a zero column)
  bool judged_;               // the estimator gives outlier verdicts (cleaning applies)
  bool in_startup_;           // the estimator is in its start-up (asked after each update only while true)
  bool uses_estimate_;        // the source's regressor depends on θ (ARMAX/OE/BJ)
  bool batch_;                // the estimator solves on all samples when read (kind() "batch")
  long next_batch_read_ = 0;  // batch_ and uses_estimate_: the update at which its estimate is next tracked
  std::optional<RecursiveLeastSquares> shadow_;  // θ for the regressors during a robust start-up
  int updates_ = 0, rejected_ = 0, failed_ = 0;  // failed_: rejected as numerical failures
};

// Fit % = 100·(1 − ‖y − ŷ‖/‖y − ȳ‖) and RMS, accumulated in one pass (Welford for ‖y − ȳ‖²).
class FitAccumulator {
 public:
  void Add(double y, double yhat) {
    ++count_;
    const double delta = y - mean_;
    mean_ += delta / static_cast<double>(count_);
    dev_ += delta * (y - mean_);
    err_ += (y - yhat) * (y - yhat);
  }
  long count() const { return count_; }
  bool finite() const { return std::isfinite(err_) && std::isfinite(dev_); }
  double Percent() const { return 100.0 * (1.0 - std::sqrt(err_) / std::sqrt(dev_)); }
  double Rms() const { return std::sqrt(err_ / static_cast<double>(count_)); }

 private:
  long count_ = 0;
  double mean_ = 0, dev_ = 0, err_ = 0;
};

// One-step and simulation scoring of θ, one row at a time (rows of one segment, in order).
class Scoring {
 public:
  // `first_row`: the 0-based record row of the segment's first row (for the row of a diverging simulation).
  Scoring(const DataSource& source, const Eigen::VectorXd& theta, int first_row = 0)
      : first_row_(first_row),
        one_step_source_(source.Clone()),
        simulation_source_(source.Clone()),
        theta_(theta),
        z_(source.num_parameters()),
        t0_(source.first_regression_index()) {
    one_step_source_->Reset();
    simulation_source_->Reset();
    one_step_source_->SetEstimate(theta_);
    simulation_source_->SetEstimate(theta_);
  }

  // A further experiment starts at the next row: one-step regressors and the simulation restart from its
  // own first t0 measured outputs.
  void Restart() {
    one_step_source_->Restart();
    simulation_source_->Restart();
    experiment_row_ = 0;
  }

  void Row(const Eigen::VectorXd& row) {
    const double y = row(one_step_source_->output_column());
    if (one_step_source_->Regressor(row, z_) && std::isfinite(y) && AllFinite(z_)) {
      const double yhat = theta_.dot(z_);
      one_step_.Add(y, yhat);
      one_step_size_ = std::max(one_step_size_, std::isfinite(yhat) ? std::abs(yhat) : HUGE_VAL);
    }
    one_step_source_->PushOutput(y);
    if (std::isfinite(y)) y_scale_ = std::max(y_scale_, std::abs(y));
    if (simulation_source_->dynamic()) {
      if (simulation_source_->Regressor(row, z_)) {
        const double yhat = theta_.dot(z_);
        const double size = std::isfinite(yhat) ? std::abs(yhat) : HUGE_VAL;
        if (size > (highs_.empty() ? 0.0 : highs_.back().second)) highs_.emplace_back(row_, size);
        if (std::isfinite(y) && std::isfinite(yhat)) simulation_.Add(y, yhat);
        simulation_source_->PushOutput(yhat);
      } else {
        simulation_source_->PushOutput(experiment_row_ < t0_ ? y : std::nan(""));
      }
    }
    ++row_;
    ++experiment_row_;
  }

  FitScores Finish(const std::string& name) const {
    IDENT_REQUIRE(one_step_.count() >= 2, "{}: fewer than 2 validation samples can be scored", name);
    FitScores scores;
    // Divergence: the first record high of |ŷ| beyond 1000 times the largest measured |y|.
    for (const auto& [row, size] : highs_)
      if (size > kDivergence * y_scale_) {
        scores.simulation_diverged_at = first_row_ + row + 1;
        break;
      }
    // An ARMAX/OE/BJ predictor filters by 1/C or 1/F: with an unstable C or F it diverges as a simulation
    // does (the same test), and has no fit %.
    const bool predictor_diverged =
        one_step_source_->uses_estimate() && (!one_step_.finite() || one_step_size_ > kDivergence * y_scale_);
    IDENT_REQUIRE(one_step_.finite() || predictor_diverged,
                  "{}: the validation fit overflows (values or predictions near 1e308); rescale the data", name);
    scores.scored = static_cast<int>(one_step_.count());
    scores.one_step = predictor_diverged ? std::nan("") : one_step_.Percent();
    scores.rms_one_step = predictor_diverged ? std::nan("") : one_step_.Rms();
    if (simulation_source_->dynamic() && simulation_.count() >= 2 && simulation_.finite() &&
        !scores.simulation_diverged_at) {
      scores.simulation = simulation_.Percent();
      scores.rms_simulation = simulation_.Rms();
    }
    return scores;
  }

 private:
  static constexpr double kDivergence = 1e3;
  int first_row_;
  std::unique_ptr<DataSource> one_step_source_, simulation_source_;
  Eigen::VectorXd theta_, z_;
  int t0_;
  int row_ = 0;             // row in the segment
  int experiment_row_ = 0;  // row in the segment's current experiment
  FitAccumulator one_step_, simulation_;
  double y_scale_ = 0;                         // largest measured |y| so far
  double one_step_size_ = 0;                   // largest |one-step ŷ|
  std::vector<std::pair<int, double>> highs_;  // (row in the segment, |ŷ|) at each new largest |ŷ|
};

// Prepares a further pass: estimator.BeginPass(); for an estimator that declines (RLS) on an ARMAX/OE/BJ
// source, the recursion simply goes on over the record again (θ̂ and its information carry on, and the
// regressors of the new pass come from the better estimate: RELS over the repeated record, Ljung &
// Söderström 1983, §3.7); *repeated counts such passes (the information then counts each sample once per
// pass). False if no further pass can change the result.
inline bool NextPass(AnyRegressionEstimator& estimator, const DataSource& source, int* repeated) {
  if (estimator.BeginPass()) return true;
  if (!source.uses_estimate()) return false;
  if (repeated) ++*repeated;
  return true;
}

// The standard errors of an estimate whose recursion ran `repeated` extra passes over the same samples
// (NextPass): its information counts each sample 1 + repeated times, so the errors are scaled back up.
inline void CorrectRepeatedPasses(FitResult& result, int repeated) {
  if (repeated > 0) result.theta_std *= std::sqrt(1.0 + repeated);
}

// Runs `pass(options)` (one pass over the estimation part, returning its (updates, rejected)) options.passes
// times, calling NextPass() between passes (`repeated` as there); the trace and on_update see the last pass only. An
// estimator that declines a further pass runs once (re-run with the trace if it was held back). Stores the
// number of passes made in *passes_run.
template <class Pass>
inline std::pair<int, int> RunPasses(AnyRegressionEstimator& estimator, const DataSource& source,
                                     const FitOptions& options, int* passes_run, int* repeated, Pass&& pass) {
  IDENT_REQUIRE(options.passes >= 1 && options.passes <= 100, "--passes {}; need 1 <= passes <= 100", options.passes);
  FitOptions quiet = options;
  quiet.trace = nullptr;
  quiet.on_update = {};
  int made = 1;
  std::pair<int, int> counts = pass(options.passes == 1 ? options : quiet);
  for (; made < options.passes; ++made) {
    if (!NextPass(estimator, source, repeated)) break;
    counts = pass(made + 1 == options.passes ? options : quiet);
  }
  if (made == 1 && options.passes > 1 && (options.trace || options.on_update)) {
    estimator.Reset();
    counts = pass(options);
  }
  if (passes_run) *passes_run = made;
  return counts;
}

inline std::pair<int, int> EstimateRows(const io::DataTable& data, Segment segment, DataSource& source,
                                        AnyRegressionEstimator& estimator, const FitOptions& options,
                                        int* passes_run = nullptr, int* repeated = nullptr) {
  source.ClearEstimate();  // ARMAX/OE/BJ: no estimate from an earlier fit on this source
  return RunPasses(estimator, source, options, passes_run, repeated, [&](const FitOptions& o) {
    Estimation estimation(source, estimator, o);
    Eigen::VectorXd row(data.values.cols());
    for (int r = segment.first; r < segment.first + segment.count; ++r) {
      if (r > segment.first && data.StartsExperiment(r)) estimation.Restart();
      row = data.values.row(r).transpose();
      estimation.Row(row, r);
    }
    return estimation.Finish(data.source);
  });
}

inline FitResult Summarise(const DataSource& source, const AnyRegressionEstimator& estimator, Segment estimation,
                           Segment validation) {
  FitResult result;
  result.estimator = estimator.name();
  result.kind = estimator.kind();
  result.structure = source.structure();
  result.parameter_names = source.parameter_names();
  result.theta = estimator.parameters();
  result.theta_std = estimator.covariance().diagonal().cwiseMax(0).cwiseSqrt();
  result.noise_std = estimator.noise_std();
  result.nu = estimator.nu();
  result.Dy = estimator.Dy();
  result.samples_estimation = estimation.count;
  result.samples_validation = validation.count;
  result.cleaned = source.cleaned();
  result.lock_in = estimator.lock_in();
  return result;
}

// Throws DataError if the result of the estimation part cannot be reported (see UnusableResult), or if the
// model's one-step predictor is unstable (DataSource::UnstablePredictor): its predictions are undefined.
inline void RequireUsable(const FitResult& result, const AnyRegressionEstimator& estimator, const DataSource& source,
                          const std::string& name) {
  std::string why = UnusableResult(estimator, result.parameter_names, result.updates);
  if (why.empty()) why = source.UnstablePredictor(result.theta);
  if (!why.empty()) throw UnusableFit(name, why);
}

// Σ of (y², z_1², …, z_ρ²) and the count over rows fed to Add (usable samples only).
class MeanSquares {
 public:
  explicit MeanSquares(DataSource& source)
      : source_(source), z_(source.num_parameters()), sum_(Eigen::VectorXd::Zero(source.num_parameters() + 1)) {
    source_.Reset();
  }
  void Restart() { source_.Restart(); }  // a further experiment starts at the next row
  void Add(const Eigen::VectorXd& row) {
    const double y = row(source_.output_column());
    if (source_.Regressor(row, z_) && std::isfinite(y) && AllFinite(z_)) {
      sum_(0) += y * y;
      sum_.tail(z_.size()) += z_.cwiseAbs2();
      ++count_;
    }
    source_.PushOutput(y);
  }
  Eigen::VectorXd Get() {
    source_.Reset();
    return count_ > 0 ? Eigen::VectorXd(sum_ / static_cast<double>(count_)) : sum_;
  }

 private:
  DataSource& source_;
  Eigen::VectorXd z_, sum_;
  long count_ = 0;
};

}  // namespace ident::workflow::internal
