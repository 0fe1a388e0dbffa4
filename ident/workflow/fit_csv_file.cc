// The streamed workflow of ident/workflow/fit.h: FitCsvFile and its passes over a CSV file in constant memory.
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
#include "ident/workflow/fit_record.h"
#include "ident/workflow/internal/fit_steps.h"

namespace ident::workflow {

using internal::Estimation;
using internal::MeanSquares;
using internal::RequireUsable;
using internal::RunningMean;
using internal::RunPasses;
using internal::Scoring;
using internal::Split;
using internal::Summarise;

long CountCsvDataRows(const std::string& path) {
  std::ifstream in(path, std::ios::in | std::ios::binary);
  if (!in) throw DataError(fmt::format("cannot open '{}': {}", path, std::strerror(errno)));
  io::internal::CountCsvFileOpened();
  // A line ends at LF or CR (CRLF: an empty line between them, not counted) and counts if it has a
  // character other than ' ' and '\t' and the first such is not '#' (the reader skips the others: blank
  // lines and comments). Past a line's first such character, memchr finds its end.
  std::vector<char> block(1 << 20);
  long lines = 0;
  enum { kBlank, kContent, kComment } state = kBlank;  // of the current line so far
  while (in) {
    in.read(block.data(), static_cast<std::streamsize>(block.size()));
    const char* p = block.data();
    const char* const end = p + in.gcount();
    const char* next_cr = nullptr;  // the first CR at or after p (end: none); null: not searched yet
    while (p < end) {
      if (state == kBlank) {
        const char c = *p;
        if (c == ' ' || c == '\t' || c == '\n' || c == '\r') {
          ++p;
          continue;
        }
        state = c == '#' ? kComment : kContent;
      }
      if (next_cr == nullptr || next_cr < p) {
        next_cr = static_cast<const char*>(std::memchr(p, '\r', static_cast<std::size_t>(end - p)));
        if (next_cr == nullptr) next_cr = end;
      }
      const char* lf = static_cast<const char*>(std::memchr(p, '\n', static_cast<std::size_t>(next_cr - p)));
      const char* const line_end = lf ? lf : next_cr;
      if (line_end == end) break;  // the line goes on in the next block
      lines += state == kContent;
      state = kBlank;
      p = line_end + 1;
    }
  }
  if (in.bad()) throw DataError(fmt::format("cannot read '{}': {}", path, std::strerror(errno)));
  lines += state == kContent;
  return lines > 0 ? lines - 1 : 0;  // minus the header
}

namespace {

// The layout of a CSV file from its header and its data lines (`data_lines`: CountCsvDataRows(path), counted
// here if negative).
CsvLayout LayOut(const std::string& path, const io::CsvOptions& csv, const DataSource& source,
                 const FitOptions& options, long data_lines = -1) {
  io::CsvReader header(path, csv);
  CsvLayout layout;
  layout.columns = header.num_columns();
  if (data_lines < 0) data_lines = CountCsvDataRows(path);
  layout.rows = data_lines + (header.generated_names() ? 1 : 0);  // no header: its line is a row
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

// Passes 3 and 4 of FitCsvFile (fit.h), given the layout (pass 1) and the detrending offsets (pass 2).
FitResult StreamCsvFile(const std::string& path, const io::CsvOptions& csv, DataSource& source,
                        AnyRegressionEstimator& estimator, const FitOptions& options, const CsvLayout& layout,
                        const Eigen::VectorXd& offset) {
  const long rows = layout.rows;
  const Segment estimation = layout.estimation, validation = layout.validation;  // captured below (clang 14)
  Eigen::VectorXd row(layout.columns);

  // Pass 3: estimate on the estimation part; with split < 1 score the rest in the same pass. With
  // options.passes > 1 the passes before the last read the estimation part only.
  if (options.trace) WriteTraceHeader(options.trace, source.num_parameters());
  int passes = 1, repeated = 0;
  source.ClearEstimate();  // ARMAX/OE/BJ: no estimate from an earlier fit on this source
  if (options.passes > 1) {
    FitOptions earlier = options;
    earlier.passes = options.passes - 1;
    earlier.trace = nullptr;
    earlier.on_update = {};
    RunPasses(estimator, source, earlier, &passes, &repeated, [&](const FitOptions& o) {
      Estimation estimating(source, estimator, o);
      io::CsvReader reader(path, csv);
      for (int r = 0; r < estimation.count && reader.Next(row); ++r) {
        row -= offset;
        estimating.Row(row, r);
      }
      return estimating.Finish(path);
    });
    if (passes == options.passes - 1 && internal::NextPass(estimator, source, &repeated)) {
      ++passes;
    } else {
      estimator.Reset();
      source.ClearEstimate();
      passes = 1;
      repeated = 0;
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
    internal::CorrectRepeatedPasses(result, repeated);
    result.passes = passes;
    result.updates = updates;
    result.rejected = rejected;
    RequireUsable(result, estimator, path);
    scoring = std::make_unique<Scoring>(source, result.theta, validation.first);
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
                                  const CsvLayout& layout, const Eigen::VectorXd& offset) {
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

Eigen::VectorXd CsvEstimationMeanSquares(const std::string& path, const io::CsvOptions& csv, DataSource& source,
                                         const FitOptions& options) {
  return DataErrorsFirst(path, csv, [&] {
    const CsvLayout layout = LayOut(path, csv, source, options);
    const Eigen::VectorXd offset = DetrendOffsets(path, csv, source, options, layout.estimation);
    return StreamMeanSquares(path, csv, source, layout, offset);
  });
}

FitResult FitCsvFile(const std::string& path, const io::CsvOptions& csv, DataSource& source,
                     AnyRegressionEstimator& estimator, const FitOptions& options) {
  return DataErrorsFirst(path, csv, [&] {
    const CsvLayout layout = LayOut(path, csv, source, options);
    const Eigen::VectorXd offset = DetrendOffsets(path, csv, source, options, layout.estimation);
    return StreamCsvFile(path, csv, source, estimator, options, layout, offset);
  });
}

CsvLayout CheckCsvLayout(const std::string& path, const io::CsvOptions& csv, const DataSource& source,
                         const FitOptions& options, long data_lines) {
  return DataErrorsFirst(path, csv, [&] { return LayOut(path, csv, source, options, data_lines); });
}

FitResult FitCsvFile(const std::string& path, const io::CsvOptions& csv, DataSource& source, FitPlan& plan,
                     const CsvLayout& layout) {
  return DataErrorsFirst(path, csv, [&] {
    const Eigen::VectorXd offset = DetrendOffsets(path, csv, source, plan.options, layout.estimation);
    if (plan.scaled_prior) plan.UseScaledPrior(StreamMeanSquares(path, csv, source, layout, offset));
    return StreamCsvFile(path, csv, source, *plan.estimator, plan.options, layout, offset);
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

}  // namespace ident::workflow
