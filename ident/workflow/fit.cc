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
#include "ident/workflow/internal/fit_steps.h"

namespace ident::workflow {

using internal::EstimateRows;
using internal::MeanSquares;
using internal::RequireUsable;
using internal::RobustOffset;
using internal::RunningMean;
using internal::Scoring;
using internal::Split;
using internal::Summarise;

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

std::pair<Segment, Segment> PrepareData(io::DataTable& data, const DataSource& source, const FitOptions& options,
                                        std::vector<std::pair<int, double>>* means) {
  const auto [estimation, validation] = Split(data.num_rows(), source, options, data.source);
  if (means) means->clear();
  if (options.detrend == Detrend::kMean) {
    const int robust = internal::RobustOffsetColumn(options, source);
    for (int c : source.used_columns()) {
      double m = 0;
      if (c == robust) {
        m = RobustOffset(data.values.col(c).head(estimation.count), data.source, data.names[c]);
      } else {
        RunningMean mean;
        for (int r = 0; r < estimation.count; ++r) mean.Add(data.values(r, c));
        m = mean.Get(data.source, data.names[c]);
      }
      data.values.col(c).array() -= m;
      if (means) means->emplace_back(c, m);
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

std::pair<int, int> Estimate(
    const io::DataTable& data, Segment segment, DataSource& source, AnyRegressionEstimator& estimator, std::FILE* trace,
    const OutlierDecision& decision,
    const std::function<void(int row, const StepReport& step, const AnyRegressionEstimator&)>& on_update) {
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
  Scoring scoring(source, theta, segment.first);
  Eigen::VectorXd row(data.values.cols());
  for (int r = segment.first; r < segment.first + segment.count; ++r) {
    if (r > segment.first && data.StartsExperiment(r)) scoring.Restart();
    row = data.values.row(r).transpose();
    scoring.Row(row);
  }
  return scoring.Finish(data.source);
}

FitResult Fit(io::DataTable data, DataSource& source, AnyRegressionEstimator& estimator, const FitOptions& options) {
  const auto [estimation, validation] = PrepareData(data, source, options);
  return FitPrepared(data, estimation, validation, source, estimator, options);
}

FitResult FitPrepared(const io::DataTable& data, Segment estimation, Segment validation, DataSource& source,
                      AnyRegressionEstimator& estimator, const FitOptions& options) {
  if (options.trace) WriteTraceHeader(options.trace, source.num_parameters());
  int passes = 1, repeated = 0;
  const auto [updates, rejected] = EstimateRows(data, estimation, source, estimator, options, &passes, &repeated);
  FitResult result = Summarise(source, estimator, estimation, validation);
  internal::CorrectRepeatedPasses(result, repeated);
  result.passes = passes;
  result.updates = updates;
  result.rejected = rejected;
  RequireUsable(result, estimator, source, data.source);
  result.validation = Score(data, validation, source, result.theta);
  return result;
}

Eigen::VectorXd EstimationMeanSquares(const io::DataTable& prepared, Segment estimation, DataSource& source) {
  MeanSquares squares(source);
  Eigen::VectorXd row(prepared.values.cols());
  for (int r = estimation.first; r < estimation.first + estimation.count; ++r) {
    if (r > estimation.first && prepared.StartsExperiment(r)) squares.Restart();
    row = prepared.values.row(r).transpose();
    squares.Add(row);
  }
  return squares.Get();
}

}  // namespace ident::workflow
