#include "ident/workflow/fit.h"

#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <memory>

#include <fmt/format.h>
#include <Eigen/Eigenvalues>

#include "common/error.h"

namespace ident::workflow {
namespace {

// The estimation and validation segments of an n-row record; checks they are long enough.
std::pair<Segment, Segment> Split(int n, const DataSource& source, const FitOptions& options, const std::string& name) {
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
        z_(source.num_parameters()),
        z_measured_(source.num_parameters()),
        ZtZ_(Eigen::MatrixXd::Zero(source.num_parameters(), source.num_parameters())),
        max_abs_(Eigen::VectorXd::Zero(source.num_parameters())),
        judged_(estimator.judges_outliers()),
        in_startup_(estimator.in_startup()) {
    source_.Reset();
  }

  // `r` is the 0-based row index in the record (the trace prints r + 1).
  void Row(const Eigen::VectorXd& row, int r) {
    const double y = row(source_.output_column());
    bool flagged = false;
    double y_hat = std::nan(""), scale = std::nan("");
    if (source_.Regressor(row, z_)) {
      // y(t−1) was cleaned: keep the reading of it (additive outlier or innovation) that predicts y(t) better.
      if (source_.MeasuredRegressor(z_measured_) &&
          std::abs(y - estimator_.Predict(z_measured_)) < std::abs(y - estimator_.Predict(z_))) {
        source_.RestoreMeasured();
        z_ = z_measured_;
      }
      const StepReport report = estimator_.Update(y, z_);
      if (in_startup_ && !estimator_.in_startup()) {  // the robust start is made: the model judges from now on
        in_startup_ = false;
        source_.EndCleaningWarmUp();
      }
      flagged = decision_.Flags(report);
      // Every prediction ŷ goes to the cleaner (its gross-error test compares |y − ŷ| with the robust
      // scale of all recent prediction errors); a flagged output is rebuilt from ŷ and the noise scale.
      y_hat = y - report.prediction_error;
      scale = estimator_.noise_std();
      if (report.updated()) {
        ++updates_;
        ZtZ_.selfadjointView<Eigen::Lower>().rankUpdate(z_);
        max_abs_ = max_abs_.cwiseMax(z_.cwiseAbs());
        if (on_update_) on_update_(r, estimator_);
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
  }

  // The end of the pass: a start-up that still waits starts from every sample seen. Identifiability:
  // every regressor must vary and none may be a combination of the others.
  std::pair<int, int> Finish(const std::string& name) {
    estimator_.FinishStartup();
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
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(C);
    IDENT_REQUIRE(eig.eigenvalues()(0) > 1e-12 * rho,
                  "{}: the regressors are collinear over the estimation part (smallest eigenvalue of their "
                  "correlation matrix {:.3g}); the model is not identifiable (if a gross outlier has moved the "
                  "detrending mean, try --detrend none)",
                  name, eig.eigenvalues()(0));
    return {updates_, rejected_};
  }

 private:
  DataSource& source_;
  AnyRegressionEstimator& estimator_;
  std::FILE* trace_;
  double min_information_;
  OutlierDecision decision_;
  std::function<void(int row, const AnyRegressionEstimator&)> on_update_;
  Eigen::VectorXd z_, z_measured_;
  Eigen::MatrixXd ZtZ_;
  Eigen::VectorXd max_abs_;  // largest |z_i| over the updates (tells underflowing squares from a zero column)
  bool judged_;              // the estimator gives outlier verdicts (cleaning applies)
  bool in_startup_;          // the estimator is in its start-up (asked after each update only while true)
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
  Scoring(const DataSource& source, const Eigen::VectorXd& theta)
      : one_step_source_(source.Clone()),
        simulation_source_(source.Clone()),
        theta_(theta),
        z_(source.num_parameters()),
        t0_(source.first_regression_index()) {
    one_step_source_->Reset();
    simulation_source_->Reset();
  }

  void Row(const Eigen::VectorXd& row) {
    const double y = row(one_step_source_->output_column());
    if (one_step_source_->Regressor(row, z_) && std::isfinite(y) && z_.allFinite()) one_step_.Add(y, theta_.dot(z_));
    one_step_source_->PushOutput(y);
    if (simulation_source_->dynamic()) {
      if (simulation_source_->Regressor(row, z_)) {
        const double yhat = theta_.dot(z_);
        if (std::isfinite(y) && std::isfinite(yhat)) simulation_.Add(y, yhat);
        simulation_source_->PushOutput(yhat);
      } else {
        simulation_source_->PushOutput(row_ < t0_ ? y : std::nan(""));
      }
    }
    ++row_;
  }

  FitScores Finish(const std::string& name) const {
    IDENT_REQUIRE(one_step_.count() >= 2, "{}: fewer than 2 validation samples can be scored", name);
    IDENT_REQUIRE(one_step_.finite(),
                  "{}: the validation fit overflows (values or predictions near 1e308); rescale the data", name);
    FitScores scores;
    scores.scored = static_cast<int>(one_step_.count());
    scores.one_step = one_step_.Percent();
    scores.rms_one_step = one_step_.Rms();
    if (simulation_source_->dynamic() && simulation_.count() >= 2 && simulation_.finite()) {
      scores.simulation = simulation_.Percent();
      scores.rms_simulation = simulation_.Rms();
    }
    return scores;
  }

 private:
  std::unique_ptr<DataSource> one_step_source_, simulation_source_;
  Eigen::VectorXd theta_, z_;
  int t0_;
  int row_ = 0;
  FitAccumulator one_step_, simulation_;
};

// Runs `pass(options)` (one pass over the estimation part, returning its (updates, rejected)) options.passes
// times, calling estimator.BeginPass() between passes; the trace and on_update see the last pass only. An
// estimator that declines a further pass runs once (re-run with the trace if it was held back). Stores the
// number of passes made in *passes_run.
template <class Pass>
std::pair<int, int> RunPasses(AnyRegressionEstimator& estimator, const FitOptions& options, int* passes_run,
                              Pass&& pass) {
  IDENT_REQUIRE(options.passes >= 1 && options.passes <= 100, "--passes {}; need 1 <= passes <= 100", options.passes);
  FitOptions quiet = options;
  quiet.trace = nullptr;
  quiet.on_update = {};
  int made = 1;
  std::pair<int, int> counts = pass(options.passes == 1 ? options : quiet);
  for (; made < options.passes; ++made) {
    if (!estimator.BeginPass()) break;
    counts = pass(made + 1 == options.passes ? options : quiet);
  }
  if (made == 1 && options.passes > 1 && (options.trace || options.on_update)) {
    estimator.Reset();
    counts = pass(options);
  }
  if (passes_run) *passes_run = made;
  return counts;
}

std::pair<int, int> EstimateRows(const io::DataTable& data, Segment segment, DataSource& source,
                                 AnyRegressionEstimator& estimator, const FitOptions& options,
                                 int* passes_run = nullptr) {
  return RunPasses(estimator, options, passes_run, [&](const FitOptions& o) {
    Estimation estimation(source, estimator, o);
    Eigen::VectorXd row(data.values.cols());
    for (int r = segment.first; r < segment.first + segment.count; ++r) {
      row = data.values.row(r).transpose();
      estimation.Row(row, r);
    }
    return estimation.Finish(data.source);
  });
}

FitResult Summarise(const DataSource& source, const AnyRegressionEstimator& estimator, Segment estimation,
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

// Throws DataError if the result of the estimation part cannot be reported (see UnusableResult).
void RequireUsable(const FitResult& result, const AnyRegressionEstimator& estimator, const std::string& name) {
  const std::string why = UnusableResult(estimator, result.parameter_names, result.updates);
  if (!why.empty()) throw DataError(fmt::format("{}: the result is unusable: {}", name, why));
}

}  // namespace

std::string UnusableResult(const AnyRegressionEstimator& estimator, const std::vector<std::string>& parameter_names,
                           int updates) {
  const int rho = estimator.num_parameters();
  auto name = [&](int i) {
    return i < static_cast<int>(parameter_names.size()) ? parameter_names[static_cast<std::size_t>(i)]
                                                        : fmt::format("theta{}", i + 1);
  };
  if (updates < rho + 1)
    return fmt::format(
        "only {} updates were accepted, fewer than the {} parameters + 1; the estimate rests on the "
        "prior, not on the data",
        updates, rho);
  if (estimator.in_startup())
    return fmt::format(
        "the estimator's start-up did not complete: its robust start needs a window of samples "
        "(at least 20, and 4 per parameter) with identifiable regressors, and the {} updates did not "
        "give one; the estimate is its prior's (fit a longer record, or use rls or huber)",
        updates);
  const Eigen::VectorXd theta = estimator.parameters();
  for (int i = 0; i < rho; ++i)
    if (!std::isfinite(theta(i))) return fmt::format("parameter '{}' is {}", name(i), theta(i));
  const double noise = estimator.noise_std();
  if (!std::isfinite(noise)) {
    if (estimator.nu() <= rho + 1)
      return fmt::format(
          "the noise std is {}: the estimate rests on the information of nu = {:.3g} samples, not "
          "more than the {} parameters + 1 (a forgetting factor f keeps about 1/(1 - f) samples; "
          "raise --forgetting)",
          noise, estimator.nu(), rho);
    return fmt::format("the noise std is {} (values too large: rescale the data)", noise);
  }
  const Eigen::VectorXd variance = estimator.covariance().diagonal();
  for (int i = 0; i < rho; ++i)
    if (!std::isfinite(variance(i)) || variance(i) < 0)
      return fmt::format(
          "the standard error of parameter '{}' (estimate {:.3g}) is {}: its variance {} (columns "
          "whose scales are too far apart: rescale the data; or, for a robust estimator, most samples "
          "weighted as outliers: a prior noise scale far below the residuals?)",
          name(i), theta(i), std::sqrt(variance(i)),
          std::isnan(variance(i)) ? "is undefined"
          : variance(i) < 0       ? "is negative"
                                  : "is infinite");
  return "";
}

std::pair<Segment, Segment> PrepareData(io::DataTable& data, const DataSource& source, const FitOptions& options) {
  const auto [estimation, validation] = Split(data.num_rows(), source, options, data.source);
  if (options.detrend == Detrend::kMean) {
    for (int c : source.used_columns()) {
      RunningMean mean;
      for (int r = 0; r < estimation.count; ++r) mean.Add(data.values(r, c));
      data.values.col(c).array() -= mean.Get(data.source, data.names[c]);
    }
  }
  return {estimation, validation};
}

void WriteTraceHeader(std::FILE* trace, int num_parameters) {
  fmt::memory_buffer line;
  fmt::format_to(std::back_inserter(line), "t,nu,beta,pred_err");
  for (int i = 1; i <= num_parameters; ++i) fmt::format_to(std::back_inserter(line), ",theta{}", i);
  fmt::format_to(std::back_inserter(line), ",Dy\n");
  std::fwrite(line.data(), 1, line.size(), trace);
}

void WriteTraceRow(std::FILE* trace, const TraceRow& row) {
  fmt::memory_buffer line;
  auto out = std::back_inserter(line);
  fmt::format_to(out, "{},{:.17g},{:.17g},{:.17g}", row.t, row.nu, row.beta, row.pred_err);
  if (row.theta)
    for (int i = 0; i < row.theta->size(); ++i) fmt::format_to(out, ",{:.17g}", (*row.theta)(i));
  fmt::format_to(out, ",{:.17g}\n", row.Dy);
  std::fwrite(line.data(), 1, line.size(), trace);
}

std::pair<int, int> Estimate(const io::DataTable& data, Segment segment, DataSource& source,
                             AnyRegressionEstimator& estimator, std::FILE* trace, const OutlierDecision& decision,
                             const std::function<void(int row, const AnyRegressionEstimator&)>& on_update) {
  FitOptions options;
  options.trace = trace;
  options.decision = decision;
  options.on_update = on_update;
  return EstimateRows(data, segment, source, estimator, options);
}

std::pair<int, int> Estimate(const io::DataTable& data, Segment segment, DataSource& source,
                             AnyRegressionEstimator& estimator, const FitOptions& options, int* passes_run) {
  return EstimateRows(data, segment, source, estimator, options, passes_run);
}

FitScores Score(const io::DataTable& data, Segment segment, DataSource& source, const Eigen::VectorXd& theta) {
  Scoring scoring(source, theta);
  Eigen::VectorXd row(data.values.cols());
  for (int r = segment.first; r < segment.first + segment.count; ++r) {
    row = data.values.row(r).transpose();
    scoring.Row(row);
  }
  return scoring.Finish(data.source);
}

FitResult Fit(io::DataTable data, DataSource& source, AnyRegressionEstimator& estimator, const FitOptions& options) {
  const auto [estimation, validation] = PrepareData(data, source, options);
  if (options.trace) WriteTraceHeader(options.trace, source.num_parameters());
  int passes = 1;
  const auto [updates, rejected] = EstimateRows(data, estimation, source, estimator, options, &passes);
  FitResult result = Summarise(source, estimator, estimation, validation);
  result.passes = passes;
  result.updates = updates;
  result.rejected = rejected;
  RequireUsable(result, estimator, data.source);
  result.validation = Score(data, validation, source, result.theta);
  return result;
}

long CountCsvDataRows(const std::string& path) {
  std::ifstream in(path, std::ios::in | std::ios::binary);
  if (!in) throw DataError(fmt::format("cannot open '{}': {}", path, std::strerror(errno)));
  // A line ends at LF or CR (CRLF: an empty line between them, not counted) and counts if it has a
  // character other than ' ' and '\t' (the reader skips the others).
  std::vector<char> block(1 << 16);
  long lines = 0;
  bool content = false;
  while (in) {
    in.read(block.data(), static_cast<std::streamsize>(block.size()));
    const char* const end = block.data() + in.gcount();
    for (const char* p = block.data(); p < end; ++p) {
      const char c = *p;
      if (c == '\n' || c == '\r') {
        lines += content;
        content = false;
      } else if (c != ' ' && c != '\t') {
        content = true;
      }
    }
  }
  if (in.bad()) throw DataError(fmt::format("cannot read '{}': {}", path, std::strerror(errno)));
  lines += content;
  return lines > 0 ? lines - 1 : 0;  // minus the header
}

namespace {

// The rows of a CSV file: the header's reader, the number of data rows and the (estimation, validation) split.
struct CsvLayout {
  int columns = 0;
  long rows = 0;
  Segment estimation, validation;
};
CsvLayout LayOut(const std::string& path, const io::CsvOptions& csv, const DataSource& source,
                 const FitOptions& options) {
  io::CsvReader header(path, csv);
  CsvLayout layout;
  layout.columns = header.num_columns();
  layout.rows = CountCsvDataRows(path);
  if (layout.rows == 0) {
    Eigen::VectorXd row(layout.columns);
    header.Next(row);  // throws "no data rows after the header"
  }
  IDENT_REQUIRE(layout.rows <= 2'000'000'000L, "{}: {} rows; at most 2e9 are supported", path, layout.rows);
  std::tie(layout.estimation, layout.validation) = Split(static_cast<int>(layout.rows), source, options, path);
  return layout;
}

// Detrending offsets of a CSV file: the estimation-part means of the used columns (NaN = missing skipped),
// zero with Detrend::kNone.
Eigen::VectorXd DetrendOffsets(const std::string& path, const io::CsvOptions& csv, const DataSource& source,
                               const FitOptions& options, Segment estimation) {
  io::CsvReader reader(path, csv);
  Eigen::VectorXd offset = Eigen::VectorXd::Zero(reader.num_columns()), row(reader.num_columns());
  if (options.detrend == Detrend::kMean) {
    std::vector<RunningMean> means(static_cast<std::size_t>(reader.num_columns()));
    const std::vector<int> used = source.used_columns();
    for (int r = 0; r < estimation.count && reader.Next(row); ++r)
      for (int c : used) means[c].Add(row(c));
    for (int c : used) offset(c) = means[c].Get(path, reader.names()[c]);
  }
  return offset;
}

// Σ of (y², z_1², …, z_ρ²) and the count over rows fed to Add (usable samples only).
class MeanSquares {
 public:
  explicit MeanSquares(DataSource& source)
      : source_(source), z_(source.num_parameters()), sum_(Eigen::VectorXd::Zero(source.num_parameters() + 1)) {
    source_.Reset();
  }
  void Add(const Eigen::VectorXd& row) {
    const double y = row(source_.output_column());
    if (source_.Regressor(row, z_) && std::isfinite(y) && z_.allFinite()) {
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

// Runs f(); if it throws InvalidArgument, a bad row later in the file is the real problem (e.g. a ragged
// row makes the record look too short): report the data error first, as reading the whole table up
// front would.
template <class F>
auto DataErrorsFirst(const std::string& path, const io::CsvOptions& csv, F&& f) {
  try {
    return f();
  } catch (const InvalidArgument&) {
    io::CsvReader reader(path, csv);
    Eigen::VectorXd row(reader.num_columns());
    while (reader.Next(row)) {}
    throw;
  }
}

FitResult StreamCsvFile(const std::string& path, const io::CsvOptions& csv, DataSource& source,
                        AnyRegressionEstimator& estimator, const FitOptions& options) {
  // Pass 1: the header, then the number of rows (the rows are parsed and checked by the passes below).
  const CsvLayout layout = LayOut(path, csv, source, options);
  const long rows = layout.rows;
  const Segment estimation = layout.estimation, validation = layout.validation;  // captured below (clang 14)
  Eigen::VectorXd row(layout.columns);

  // Pass 2: detrending offsets (estimation-part means of the used columns, NaN = missing skipped).
  const Eigen::VectorXd offset = DetrendOffsets(path, csv, source, options, estimation);

  // Pass 3: estimate on the estimation part; with split < 1 score the rest in the same pass. With
  // options.passes > 1 the passes before the last read the estimation part only.
  if (options.trace) WriteTraceHeader(options.trace, source.num_parameters());
  int passes = 1;
  if (options.passes > 1) {
    FitOptions earlier = options;
    earlier.passes = options.passes - 1;
    earlier.trace = nullptr;
    earlier.on_update = {};
    RunPasses(estimator, earlier, &passes, [&](const FitOptions& o) {
      Estimation estimating(source, estimator, o);
      io::CsvReader reader(path, csv);
      for (int r = 0; r < estimation.count && reader.Next(row); ++r) {
        row -= offset;
        estimating.Row(row, r);
      }
      return estimating.Finish(path);
    });
    if (passes == options.passes - 1 && estimator.BeginPass()) {
      ++passes;
    } else {
      estimator.Reset();
      passes = 1;
    }
  }
  Estimation estimating(source, estimator, options);
  std::unique_ptr<Scoring> scoring;
  FitResult result;
  io::CsvReader reader(path, csv);
  int r = 0;
  auto finish_estimation = [&] {
    std::tie(result.updates, result.rejected) = estimating.Finish(path);
    const int updates = result.updates, rejected = result.rejected;
    result = Summarise(source, estimator, estimation, validation);
    result.passes = passes;
    result.updates = updates;
    result.rejected = rejected;
    RequireUsable(result, estimator, path);
    scoring = std::make_unique<Scoring>(source, result.theta);
  };
  while (reader.Next(row)) {
    row -= offset;
    if (r == estimation.count) finish_estimation();
    if (r < estimation.count)
      estimating.Row(row, r);
    else
      scoring->Row(row);
    ++r;
  }
  IDENT_REQUIRE(r == rows, "{}: {} rows were counted but {} read (file changed while reading?)", path, rows, r);
  if (!scoring) {
    // Pass 4 (split = 1): score the whole record.
    finish_estimation();
    io::CsvReader again(path, csv);
    while (again.Next(row)) {
      row -= offset;
      scoring->Row(row);
    }
  }
  result.validation = scoring->Finish(path);
  return result;
}

Eigen::VectorXd StreamMeanSquares(const std::string& path, const io::CsvOptions& csv, DataSource& source,
                                  const FitOptions& options) {
  const CsvLayout layout = LayOut(path, csv, source, options);
  const Eigen::VectorXd offset = DetrendOffsets(path, csv, source, options, layout.estimation);
  MeanSquares squares(source);
  io::CsvReader reader(path, csv);
  Eigen::VectorXd row(layout.columns);
  for (int r = 0; r < layout.estimation.count && reader.Next(row); ++r) {
    row -= offset;
    squares.Add(row);
  }
  return squares.Get();
}

}  // namespace

Eigen::VectorXd EstimationMeanSquares(const io::DataTable& prepared, Segment estimation, DataSource& source) {
  MeanSquares squares(source);
  Eigen::VectorXd row(prepared.values.cols());
  for (int r = estimation.first; r < estimation.first + estimation.count; ++r) {
    row = prepared.values.row(r).transpose();
    squares.Add(row);
  }
  return squares.Get();
}

Eigen::VectorXd CsvEstimationMeanSquares(const std::string& path, const io::CsvOptions& csv, DataSource& source,
                                         const FitOptions& options) {
  return DataErrorsFirst(path, csv, [&] { return StreamMeanSquares(path, csv, source, options); });
}

FitResult FitCsvFile(const std::string& path, const io::CsvOptions& csv, DataSource& source,
                     AnyRegressionEstimator& estimator, const FitOptions& options) {
  return DataErrorsFirst(path, csv, [&] { return StreamCsvFile(path, csv, source, estimator, options); });
}

int CheckCsvRecordLength(const std::string& path, const io::CsvOptions& csv, const DataSource& source,
                         const FitOptions& options) {
  return DataErrorsFirst(path, csv, [&] { return LayOut(path, csv, source, options).estimation.count; });
}

}  // namespace ident::workflow
