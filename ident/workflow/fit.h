// The `ident fit` workflow: split, detrend, estimate recursively, score — on a table in memory (Fit)
// or streamed from a CSV file in constant memory (FitCsvFile).
//
// Protocol (datasets/README.md): the first ⌊split·N⌋ rows estimate, the rest validate (split = 1:
// estimate and validate on the whole record). Detrend "mean" subtracts the estimation-part mean of
// every column the model uses from all rows (for a robust estimator on a dynamic structure, the output's
// mean after a Hampel filter: FitOptions::robust_offset). Inside each segment regression starts at t0 (models/arx.h).
// Fit % = 100·(1 − ‖y − ŷ‖/‖y − ȳ‖) over the scored validation samples (t ≥ t0 of the segment; ȳ their
// mean); "one-step" uses measured past outputs, "simulation" (ARX only) feeds back the model's own
// output after the first t0 measured samples.
//
// Streaming (FitCsvFile), memory independent of the number of rows:
//   pass 1  count the data rows (non-blank lines after the header; no number parsing; CheckCsvLayout
//           takes a count the caller has made)
//   pass 2  detrend "mean": the estimation-part means of the used columns (reads ⌊split·N⌋ rows)
//   (ScanCsvFirstPass makes passes 1 and 2 in one read of the file: see there)
//   (pass 2b, fit_record.h's FitCsvFile for RLS's data-scaled prior: the mean squares of y and the
//           regressors over the estimation part, detrended)
//   pass 3  estimate on rows 1..⌊split·N⌋, then score on the rest in the same pass (split < 1);
//           with split = 1 a fourth pass scores the whole record.
//   The time column (time_column.h) is checked in pass 3, which reads every row: FitResult::time lists its
//   gaps. With its gaps to be filled (--missing), ScanCsvTime reads it in a pass of its own first, and
//   every pass reads each gap's missing rows before the row that ends it.
// It gives the same numbers as Fit(ReadCsv(path)) up to rounding in the fit-% sums.
#pragma once

#include <cstdio>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "common/error.h"
#include "ident/io/csv.h"
#include "ident/regression/outlier_decision.h"
#include "ident/regression/regression_estimator.h"
#include "ident/workflow/data_source.h"
#include "ident/workflow/time_column.h"

namespace ident::workflow {

enum class Detrend { kMean, kNone };

struct FitOptions {
  double split = 0.5;  // fraction of rows for estimation, in (0, 1]
  Detrend detrend = Detrend::kMean;
  // With Detrend::kMean on a dynamic structure: the output's offset is its mean after a Hampel filter
  // (spike_robust_mean.h) instead of the plain mean, so that gross errors in y do not move the operating
  // point. Set for the estimators that model outliers (EstimatorTraits::robust); the inputs keep their means.
  bool robust_offset = false;
  std::FILE* trace = nullptr;  // if set: one CSV row per update (t, nu, beta, pred_err, theta…, Dy)
  // Each regressor's Σ z_i² over the estimation part must reach this, else InvalidArgument: the
  // default flat prior carries information 1e-12 per parameter (RegressionPrior::Flat) and would bias
  // θ̂ on data of tiny scale (values near 1e-150) by more than 1e-6 relative. 0 disables the check
  // (the command line does so when an explicit prior is given).
  double min_regressor_information = 1e-6;
  OutlierDecision decision;  // which updates count as outliers for regressor cleaning
  // Passes over the estimation part (AnyRegressionEstimator::BeginPass): each further pass re-runs the
  // recursion from the previous pass's estimate, regressor cleaning included; estimators for which a
  // further pass cannot change the result (RLS, batch) run once, except on ARMAX/OE/BJ, where RLS goes on
  // over the record again (internal::NextPass). The trace shows the last pass.
  int passes = 1;
  // If set: called after every accepted update with the (0-based) row, the step (weight β(t), ν(t), prediction
  // error) and the estimator (e.g. for parameter plots).
  std::function<void(int row, const StepReport& step, const AnyRegressionEstimator&)> on_update;
  // If set: called with the (0-based) row before each row of every pass over the estimation part (progress).
  std::function<void(int row)> on_row;
};

struct FitScores {
  double one_step = 0;  // fit %
  double rms_one_step = 0;
  std::optional<double> simulation;  // fit % (dynamic models only)
  std::optional<double> rms_simulation;
  int scored = 0;  // validation samples scored
  // An unstable model: the 1-based row at which the simulated output first left 1000 times the segment's
  // largest measured |y| (or stopped being finite). The simulation then has no fit % (simulation unset).
  std::optional<int> simulation_diverged_at;
};

// A fit whose result cannot be reported (UnusableResult, DataSource::UnstablePredictor): a DataError of its
// own, so that a caller fitting many structures (ident orders) can leave that one out.
// what() is "<source>: the result is unusable: <reason>"; reason() is the reason alone.
class UnusableFit : public DataError {
 public:
  UnusableFit(const std::string& source, std::string reason)
      : DataError(source + ": the result is unusable: " + reason), reason_(std::move(reason)) {}
  const std::string& reason() const { return reason_; }

 private:
  std::string reason_;
};

struct FitResult {
  std::string estimator;
  std::string structure;
  std::vector<std::string> parameter_names;
  Eigen::VectorXd theta, theta_std;
  double noise_std = 0;
  double nu = 0, Dy = 0;
  int samples_estimation = 0, samples_validation = 0;
  std::string validation_data;    // a separate validation record (ident fit --validate); "" for the record's own
  std::string kind;               // "recursive" or "batch"
  int passes = 1;                 // passes over the estimation part that ran
  int updates = 0, rejected = 0;  // estimator steps taken / rejected (missing or invalid samples), last pass
  long cleaned = 0;               // outputs cleaned (--clean-regressors on); the equations that hold them are left out
  std::optional<LockInStatus> lock_in;  // the robust estimators' lock-in safeguard at the end of estimation
  FitScores validation;
  // The record's time column (workflow/time_column.h); null when there is none or it was not checked.
  std::optional<TimeCheck> time;
};

// The row range [first, first + count) of a table.
struct Segment {
  int first = 0;
  int count = 0;
};

// Splits and detrends `data` in place as described above and returns (estimation, validation).
// Throws InvalidArgument if split ∉ (0, 1] or a part is too short for the structure.
// `means`, if given, receives (column, subtracted mean) of every detrended column.
std::pair<Segment, Segment> PrepareData(io::DataTable& data, const DataSource& source, const FitOptions& options,
                                        std::vector<std::pair<int, double>>* means = nullptr);

// Runs the estimator over the segment (one Update per regression), writing trace rows if asked.
// Each measured output is then stored for later regressors through source.PushCheckedOutput with
// the one-step prediction, the estimator's noise scale and decision.Flags(report).
// Returns the number of updates and rejected steps (of the last pass, see FitOptions::passes). Throws
// InvalidArgument if the regressors of the segment are constant or collinear (the model is not
// identifiable from them).
std::pair<int, int> Estimate(
    const io::DataTable& data, Segment segment, DataSource& source, AnyRegressionEstimator& estimator, std::FILE* trace,
    const OutlierDecision& decision = {},
    const std::function<void(int row, const StepReport& step, const AnyRegressionEstimator&)>& on_update = {});

// The same with every option of `options` that applies (trace, decision, on_update, min_regressor_information,
// passes); `passes_run`, if given, receives the number of passes made.
std::pair<int, int> Estimate(const io::DataTable& data, Segment segment, DataSource& source,
                             AnyRegressionEstimator& estimator, const FitOptions& options, int* passes_run = nullptr);

// Why the estimator's result after `updates` accepted updates cannot be reported, or "" if it can: θ, its
// standard errors and the noise scale must be finite, at least ρ + 1 updates must have been accepted and a
// data-driven start-up must have completed (the parameters and a noise scale determined by the data, not
// by the prior).
std::string UnusableResult(const AnyRegressionEstimator& estimator, const std::vector<std::string>& parameter_names,
                           int updates);

// One-step and (for dynamic sources) simulation scores of parameters θ on the segment.
FitScores Score(const io::DataTable& data, Segment segment, DataSource& source, const Eigen::VectorXd& theta);

// Mean squares over the usable samples of the estimation part of a prepared (split and detrended)
// table: (mean y², mean z_1², …, mean z_ρ²), for RegressionPrior::Flat(mean_squares). Zero if no sample
// is usable; an entry overflows to +inf for values beyond ~1e154. `source` is Reset() before and after.
Eigen::VectorXd EstimationMeanSquares(const io::DataTable& prepared, Segment estimation, DataSource& source);

// The same for a CSV file, streamed (the detrending offsets as FitCsvFile computes them, then one pass
// over the estimation part).
Eigen::VectorXd CsvEstimationMeanSquares(const std::string& path, const io::CsvOptions& csv, DataSource& source,
                                         const FitOptions& options);

// PrepareData + Estimate + Score.
FitResult Fit(io::DataTable data, DataSource& source, AnyRegressionEstimator& estimator, const FitOptions& options);

// Estimate + Score on a table PrepareData has already split and detrended into (estimation, validation).
FitResult FitPrepared(const io::DataTable& prepared, Segment estimation, Segment validation, DataSource& source,
                      AnyRegressionEstimator& estimator, const FitOptions& options);

// The same on a CSV file, streamed (see above). `source` must have been built for the file's columns.
// Throws DataError for unreadable/bad data (file:line:column), InvalidArgument as Fit does.
FitResult FitCsvFile(const std::string& path, const io::CsvOptions& csv, DataSource& source,
                     AnyRegressionEstimator& estimator, const FitOptions& options);

// The rows of a CSV file to be streamed: its number of columns and data rows, and their (estimation,
// validation) split.
struct CsvLayout {
  int columns = 0;
  long rows = 0;
  Segment estimation, validation;
};

// CheckCsvRecordLength's checks, returning the layout; `data_lines` is CountCsvDataRows(path) when the caller
// has it (negative: counted here). With `filled` (ScanCsvTime's check, --missing) the layout is that of the
// record with each gap's missing rows inserted, and their TimeGap::filled set.
CsvLayout CheckCsvLayout(const std::string& path, const io::CsvOptions& csv, const DataSource& source,
                         const FitOptions& options, long data_lines = -1, TimeCheck* filled = nullptr);

// The layout of a CSV file and its detrending offsets (Detrend::kMean) from one read of the file: the first
// pass of a streamed fit, which reads each byte once where CheckCsvLayout and the means pass read the
// estimation part twice. The file is read in two parts:
//   tail  the lines from a byte x on are counted (CountCsvDataRows's count, no number parsing); x is a line
//         start a margin (0.2 % of the rows, at least 4 096) before where the estimation part probably ends,
//         as the bytes per line of 16 samples of 16 KiB spread over the file place it;
//   head  the rows before x are parsed in order and summed for the offsets (DetrendSums) while they are
//         certainly in the estimation part, r < ⌊split·(tail + r + 1)⌋; later rows of the head are held
//         (x past the estimation part) until the count is complete.
// Then the estimation part's rows past the head, if any, are read from x on (the margin: a few rows read twice).
// The sums take the estimation rows in file order, so the offsets are the means pass's bit for bit. If the
// held rows would exceed 2^18 values, or the rows past the head cannot be read there, the means pass is made
// after all (means_pass). With `mean_squares` (a source affine in its rows, as FitCsvFile's data-scaled prior
// takes it) the mean squares of the estimation part come with the offsets.
// No value (the caller counts and reads as before) for: Detrend::kNone, a split outside (0, 1], a file that is
// not regular, a first 16 KiB with a comment, a sample with fewer than two line ends, a margin that reaches back
// into the header, no LF within a line's length past the point guessed. Throws DataError for a bad row in the head
// (file:line), InvalidArgument as CheckCsvLayout does.
struct CsvFirstPass {
  CsvLayout layout;
  Eigen::VectorXd offset;                       // by column; zero for the columns the model does not use
  std::optional<Eigen::VectorXd> mean_squares;  // with `mean_squares`: CsvEstimationMeanSquares's figures
  long data_lines = 0;                          // the data lines, as CountCsvDataRows counts them
  bool means_pass = false;                      // true: the means took a pass of their own after all
};
std::optional<CsvFirstPass> ScanCsvFirstPass(const std::string& path, const io::CsvOptions& csv, DataSource& source,
                                             const FitOptions& options, bool mean_squares);

// The time column of a CSV file (time_column.h), read in one pass in constant memory: each step is judged
// against the median of the last ArrivingTimeCheck::kSteps regular steps, as rows that arrive one at a
// time are. Null when the file has no time column or the model reads it (`used_columns`). Throws the
// DataError "<path>:<line>: time column 't' does not increase: …", and for a gap that misses more samples
// than the rows before it.
std::optional<TimeCheck> ScanCsvTime(const std::string& path, const io::CsvOptions& csv,
                                     const std::vector<int>& used_columns);

// Number of data rows of a CSV file: the lines that are neither blank nor comments, minus one (the header).
// Reads the file in blocks without parsing numbers. Throws DataError if it cannot be read.
long CountCsvDataRows(const std::string& path);

// CheckCsvRecordLength for a record of `rows` rows in memory, named `name` in messages.
int CheckRecordLength(long rows, const DataSource& source, const FitOptions& options, const std::string& name);

// Checks from the header and the number of data rows alone (no number parsing, nothing of the model's
// size allocated) that the split record is long enough for `source`: throws the InvalidArgument
// "the estimation part has N rows; ... needs at least M" of Fit and FitCsvFile, or the DataError of
// the first bad row if the file has one. Cost O(file size), memory O(1).
// Returns the number of rows of the estimation part.
int CheckCsvRecordLength(const std::string& path, const io::CsvOptions& csv, const DataSource& source,
                         const FitOptions& options);

// Writes the trace header: t,nu,beta,pred_err,theta1..thetaρ,Dy
void WriteTraceHeader(std::FILE* trace, int num_parameters);

// One trace row per update, every number with 17 significant digits (reads back bit for bit; NaN and
// ±Inf as nan, inf, -inf). Neither writer throws: a write error stays in the stream's error flag, which
// the owner checks when it closes the file (OutputFile::Close).
struct TraceRow {
  long t = 0;  // 1-based row of the record
  double nu = 0, beta = 0, pred_err = 0;
  const Eigen::VectorXd* theta = nullptr;
  double Dy = 0;
};
void WriteTraceRow(std::FILE* trace, const TraceRow& row);

}  // namespace ident::workflow
