// The streamed workflow of ident/workflow/fit.h: FitCsvFile and its passes over a CSV file in constant memory.
#include "ident/workflow/fit.h"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>
#include <memory>
#include <optional>

#include <fmt/format.h>
#include <Eigen/Eigenvalues>

#include "common/error.h"
#include "ident/io/csv_read_ahead.h"
#include "ident/workflow/fit_record.h"
#include "ident/workflow/internal/csv_passes.h"
#include "ident/workflow/internal/fit_steps.h"
#include "ident/workflow/internal/shifted_mean_squares.h"

namespace ident::workflow {

using internal::DataErrorsFirst;
using internal::DetrendOffsets;
using internal::Estimation;
using internal::LayOutRows;
using internal::MeanSquares;
using internal::RecordRows;
using internal::RequireUsable;
using internal::RunningMean;
using internal::RunPasses;
using internal::Scoring;
using internal::Split;
using internal::Summarise;

namespace {

// The layout of a CSV file from its header and its data lines (`data_lines`: CountCsvDataRows(path), counted
// here if negative).
CsvLayout LayOut(const std::string& path, const io::CsvOptions& csv, const DataSource& source,
                 const FitOptions& options, long data_lines = -1, TimeCheck* filled = nullptr) {
  io::CsvReader header(path, csv);
  if (data_lines < 0) data_lines = CountCsvDataRows(path);
  long rows = data_lines + (header.generated_names() ? 1 : 0);  // no header: its line is a row
  if (filled != nullptr) {
    for (TimeGap& g : filled->gaps) {
      IDENT_REQUIRE(g.missing <= 2'000'000'000L - rows, "{}: the time gaps miss more than 2e9 rows", path);
      rows += g.missing;
      g.filled = g.missing;
    }
  }
  if (rows == 0) {
    Eigen::VectorXd row(header.num_columns());
    header.Next(row);  // throws "no data rows after the header"
  }
  return LayOutRows(path, source, options, rows, header.num_columns());
}

// The passes before the last of pass 3 (options.passes > 1), each over the estimation part; *passes and
// *repeated count them as RunPasses does, or start again at 1 and 0, with the estimator reset, when the last
// pass is not one more (internal::NextPass).
void RunEarlierCsvPasses(const std::string& path, const io::CsvOptions& csv, DataSource& source,
                         AnyRegressionEstimator& estimator, const FitOptions& options, Segment estimation,
                         const Eigen::VectorXd& offset, const TimeCheck* filled, Eigen::VectorXd& row, int* passes,
                         int* repeated) {
  FitOptions earlier = options;
  earlier.passes = options.passes - 1;
  earlier.trace = nullptr;
  earlier.on_update = {};
  RunPasses(estimator, source, earlier, passes, repeated, [&](const FitOptions& o) {
    Estimation estimating(source, estimator, o);
    RecordRows reader(path, csv, filled);
    for (int r = 0; r < estimation.count && reader.Next(row); ++r) {
      row -= offset;
      estimating.Row(row, r);
    }
    return estimating.Finish(path);
  });
  if (*passes == options.passes - 1 && internal::NextPass(estimator, source, repeated)) {
    ++*passes;
  } else {
    estimator.Reset();
    source.ClearEstimate();
    *passes = 1;
    *repeated = 0;
  }
}

// The time column's check as the rows arrive: the gaps found before (`filled`, then *time_column = −1), or
// an empty check of the used columns' time column at index *time_column; none without one.
std::optional<TimeCheck> ArrivingTimeColumn(const RecordRows& reader, const DataSource& source, const TimeCheck* filled,
                                            int* time_column) {
  std::optional<TimeCheck> time;
  *time_column = -1;
  if (filled != nullptr) {
    time = *filled;
  } else if ((*time_column = TimeColumnIndex(reader.names(), source.used_columns())) >= 0) {
    time.emplace();
    time->column = reader.names()[static_cast<std::size_t>(*time_column)];
  }
  return time;
}

// The end of the estimation part: the estimate summarised, with its passes, updates and rejections; throws if
// it is not usable.
FitResult FinishStreamedEstimation(Estimation& estimating, DataSource& source, AnyRegressionEstimator& estimator,
                                   const CsvLayout& layout, int passes, int repeated, const std::string& path) {
  FitResult result;
  std::tie(result.updates, result.rejected) = estimating.Finish(path);
  const int updates = result.updates, rejected = result.rejected;
  result = Summarise(source, estimator, layout.estimation, layout.validation);
  internal::CorrectRepeatedPasses(result, repeated);
  result.passes = passes;
  result.updates = updates;
  result.rejected = rejected;
  RequireUsable(result, estimator, source, path);
  return result;
}

// Passes 3 and 4 of FitCsvFile (fit.h), given the layout (pass 1) and the detrending offsets (pass 2).
FitResult StreamCsvFile(const std::string& path, const io::CsvOptions& csv, DataSource& source,
                        AnyRegressionEstimator& estimator, const FitOptions& options, const CsvLayout& layout,
                        const Eigen::VectorXd& offset, const TimeCheck* filled) {
  const long rows = layout.rows;
  const Segment estimation = layout.estimation, validation = layout.validation;  // captured below (clang 14)
  Eigen::VectorXd row(layout.columns);

  // Pass 3: estimate on the estimation part; with split < 1 score the rest in the same pass. With
  // options.passes > 1 the passes before the last read the estimation part only.
  if (options.trace) WriteTraceHeader(options.trace, source.num_parameters());
  int passes = 1, repeated = 0;
  source.ClearEstimate();  // ARMAX/OE/BJ: no estimate from an earlier fit on this source
  if (options.passes > 1)
    RunEarlierCsvPasses(path, csv, source, estimator, options, estimation, offset, filled, row, &passes, &repeated);
  Estimation estimating(source, estimator, options);
  std::unique_ptr<Scoring> scoring;
  FitResult result;
  RecordRows reader(path, csv, filled);
  // The time column, checked as the rows arrive (unless its gaps were found, to be filled, before).
  int time_column = -1;
  std::optional<TimeCheck> time = ArrivingTimeColumn(reader, source, filled, &time_column);
  ArrivingTimeCheck arriving;
  int r = 0;
  auto finish_estimation = [&] {
    result = FinishStreamedEstimation(estimating, source, estimator, layout, passes, repeated, path);
    scoring = std::make_unique<Scoring>(source, result.theta, validation.first);
  };
  while (reader.Next(row)) {
    if (time_column >= 0) {
      if (std::optional<TimeGap> gap = arriving.Next(row(time_column), r + 1, time->column, path, reader.line()))
        time->gaps.push_back(*gap);
    }
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
    RecordRows again(path, csv, filled);
    while (again.Next(row)) {
      row -= offset;
      scoring->Row(row);
    }
  }
  result.validation = scoring->Finish(path);
  if (time_column >= 0) time->median_step = arriving.median_step();
  result.time = std::move(time);
  return result;
}

Eigen::VectorXd StreamMeanSquares(const std::string& path, const io::CsvOptions& csv, DataSource& source,
                                  const CsvLayout& layout, const Eigen::VectorXd& offset, const TimeCheck* filled) {
  MeanSquares squares(source);
  RecordRows reader(path, csv, filled, 2);
  Eigen::VectorXd row(layout.columns);
  for (int r = 0; r < layout.estimation.count && reader.Next(row); ++r) {
    row -= offset;
    squares.Add(row);
  }
  return squares.Get();
}

}  // namespace

CsvLayout internal::LayOutRows(const std::string& path, const DataSource& source, const FitOptions& options, long rows,
                               int columns) {
  CsvLayout layout;
  layout.columns = columns;
  layout.rows = rows;
  IDENT_REQUIRE(layout.rows <= 2'000'000'000L, "{}: {} rows; at most 2e9 are supported", path, layout.rows);
  std::tie(layout.estimation, layout.validation) = Split(static_cast<int>(layout.rows), source, options, path);
  return layout;
}

Eigen::VectorXd internal::DetrendOffsets(const std::string& path, const io::CsvOptions& csv, const DataSource& source,
                                         const FitOptions& options, const CsvLayout& layout, const TimeCheck* filled,
                                         internal::ShiftedMeanSquares* squares) {
  if (options.detrend != Detrend::kMean) return Eigen::VectorXd::Zero(layout.columns);  // the file is not opened
  // Little work per row: the parsing is the pass's cost, on two threads.
  RecordRows reader(path, csv, filled, 2);
  Eigen::VectorXd row(reader.num_columns());
  DetrendSums sums(source, options, reader.num_columns(), squares);
  for (int r = 0; r < layout.estimation.count && reader.Next(row); ++r) sums.Add(row);
  return sums.Offsets(path, reader.names(), layout.columns);  // as the passes after read the rows
}

Eigen::VectorXd CsvEstimationMeanSquares(const std::string& path, const io::CsvOptions& csv, DataSource& source,
                                         const FitOptions& options) {
  return DataErrorsFirst(path, csv, [&] {
    const CsvLayout layout = LayOut(path, csv, source, options);
    const Eigen::VectorXd offset = DetrendOffsets(path, csv, source, options, layout, nullptr);
    return StreamMeanSquares(path, csv, source, layout, offset, nullptr);
  });
}

FitResult FitCsvFile(const std::string& path, const io::CsvOptions& csv, DataSource& source,
                     AnyRegressionEstimator& estimator, const FitOptions& options) {
  return DataErrorsFirst(path, csv, [&] {
    const CsvLayout layout = LayOut(path, csv, source, options);
    const Eigen::VectorXd offset = DetrendOffsets(path, csv, source, options, layout, nullptr);
    return StreamCsvFile(path, csv, source, estimator, options, layout, offset, nullptr);
  });
}

CsvLayout CheckCsvLayout(const std::string& path, const io::CsvOptions& csv, const DataSource& source,
                         const FitOptions& options, long data_lines, TimeCheck* filled) {
  return DataErrorsFirst(path, csv, [&] { return LayOut(path, csv, source, options, data_lines, filled); });
}

std::optional<TimeCheck> ScanCsvTime(const std::string& path, const io::CsvOptions& csv,
                                     const std::vector<int>& used_columns) {
  return DataErrorsFirst(path, csv, [&]() -> std::optional<TimeCheck> {
    io::CsvReadAhead reader(path, csv);
    const int column = TimeColumnIndex(reader.names(), used_columns);
    if (column < 0) return std::nullopt;
    TimeCheck check;
    check.column = reader.names()[static_cast<std::size_t>(column)];
    ArrivingTimeCheck arriving;
    Eigen::VectorXd row(reader.num_columns());
    for (long rows = 1; reader.Next(row); ++rows)
      if (std::optional<TimeGap> gap = arriving.Next(row(column), rows, check.column, path, reader.line()))
        check.gaps.push_back(*gap);
    check.median_step = arriving.median_step();
    return check;
  });
}

FitResult FitCsvFile(const std::string& path, const io::CsvOptions& csv, DataSource& source, FitPlan& plan,
                     const CsvLayout& layout, const TimeCheck* filled) {
  return DataErrorsFirst(path, csv, [&] {
    // The data-scaled prior's mean squares: in the means pass when the regressor allows, else a pass of
    // their own.
    std::optional<internal::ShiftedMeanSquares> squares;
    if (plan.scaled_prior && plan.options.detrend == Detrend::kMean && source.affine_in_rows())
      squares.emplace(source, layout.columns);
    const Eigen::VectorXd offset =
        DetrendOffsets(path, csv, source, plan.options, layout, filled, squares ? &*squares : nullptr);
    if (plan.scaled_prior)
      plan.UseScaledPrior(squares ? squares->Get(offset)
                                  : StreamMeanSquares(path, csv, source, layout, offset, filled));
    return StreamCsvFile(path, csv, source, *plan.estimator, plan.options, layout, offset, filled);
  });
}

int CheckRecordLength(long rows, const DataSource& source, const FitOptions& options, const std::string& name) {
  IDENT_REQUIRE(rows <= 2'000'000'000L, "{}: {} rows; at most 2e9 are supported", name, rows);
  return Split(static_cast<int>(rows), source, options, name).first.count;
}

int CheckCsvRecordLength(const std::string& path, const io::CsvOptions& csv, const DataSource& source,
                         const FitOptions& options) {
  return DataErrorsFirst(path, csv, [&] { return LayOut(path, csv, source, options).estimation.count; });
}

FitResult FitCsvFile(const std::string& path, const io::CsvOptions& csv, DataSource& source, FitPlan& plan,
                     const CsvFirstPass& first) {
  return DataErrorsFirst(path, csv, [&] {
    if (plan.scaled_prior)
      plan.UseScaledPrior(first.mean_squares
                              ? *first.mean_squares
                              : StreamMeanSquares(path, csv, source, first.layout, first.offset, nullptr));
    return StreamCsvFile(path, csv, source, *plan.estimator, plan.options, first.layout, first.offset, nullptr);
  });
}

}  // namespace ident::workflow
