// The building blocks of the streamed passes of ident/workflow/fit.h over a CSV file (fit_csv_file.cc and
// csv_first_pass.cc): the rows as a pass reads them, the sums of the detrending offsets, the layout of a
// counted record and the means pass (internal to ident/workflow/).
#pragma once

#include <algorithm>
#include <limits>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "common/error.h"
#include "ident/io/csv.h"
#include "ident/io/csv_read_ahead.h"
#include "ident/workflow/data_source.h"
#include "ident/workflow/fit.h"
#include "ident/workflow/internal/fit_steps.h"
#include "ident/workflow/internal/shifted_mean_squares.h"
#include "ident/workflow/time_column.h"

namespace ident::workflow::internal {

// The rows of a CSV file as a streamed fit reads them. With `filled` (time gaps to fill, --missing) each
// gap's missing rows come before the row that ends it, as FillTimeGaps inserts them into a table: NaN in
// every column but the time column, whose values step on from the gap's start by its step. The file is
// parsed ahead on `threads` threads (io::CsvReadAhead) while the caller works on the rows before.
class RecordRows {
 public:
  RecordRows(const std::string& path, const io::CsvOptions& csv, const TimeCheck* filled, int threads = 1)
      : reader_(path, csv, threads), filled_(filled != nullptr && !filled->gaps.empty() ? filled : nullptr) {
    if (filled_ == nullptr) return;
    const auto& names = reader_.names();
    time_column_ = static_cast<int>(std::find(names.begin(), names.end(), filled_->column) - names.begin());
    IDENT_REQUIRE(time_column_ < reader_.num_columns(), "{}: no time column '{}'", path, filled_->column);
    held_.resize(reader_.num_columns());
  }
  int num_columns() const { return reader_.num_columns(); }
  const std::vector<std::string>& names() const { return reader_.names(); }
  bool generated_names() const { return reader_.generated_names(); }
  long line() const { return reader_.line(); }  // of the last row read from the file

  bool Next(Eigen::Ref<Eigen::VectorXd> row) {
    if (filled_ == nullptr) {
      if (row.size() != reader_.num_columns()) [[unlikely]]
        return reader_.Next(row);  // throws: the row has the wrong size (the file changed between passes?)
      const double* const next = reader_.NextRow();
      if (next == nullptr) return false;
      row = Eigen::Map<const Eigen::VectorXd>(next, row.size());
      return true;
    }
    if (pending_ > 0) {  // the next missing row of gap gap_
      const TimeGap& g = filled_->gaps[gap_];
      row.setConstant(std::numeric_limits<double>::quiet_NaN());
      row(time_column_) = g.t_before + static_cast<double>(g.missing - pending_ + 1) * g.step;
      --pending_;
      return true;
    }
    if (holding_) {  // the row that ends the gap
      row = held_;
      holding_ = false;
      ++gap_;
      return true;
    }
    if (!reader_.Next(row)) return false;
    ++file_rows_;
    if (gap_ < filled_->gaps.size() && filled_->gaps[gap_].row == file_rows_) {
      held_ = row;
      holding_ = true;
      pending_ = filled_->gaps[gap_].missing;
      return Next(row);
    }
    return true;
  }

 private:
  io::CsvReadAhead reader_;
  const TimeCheck* filled_;
  int time_column_ = -1;
  std::size_t gap_ = 0;  // the next gap to fill
  long file_rows_ = 0, pending_ = 0;
  bool holding_ = false;
  Eigen::VectorXd held_;
};

// The estimation-part sums of the detrending offsets: a mean per used column (NaN = missing skipped), with
// FitOptions::robust_offset on a dynamic structure the output's values for SpikeRobustMean (memory O(N), as the
// robust estimators' own sample history), and with `squares` the rows for the mean squares.
class DetrendSums {
 public:
  DetrendSums(const DataSource& source, const FitOptions& options, int columns, ShiftedMeanSquares* squares)
      : used_(source.used_columns()),
        robust_(RobustOffsetColumn(options, source)),
        means_(static_cast<std::size_t>(columns)),
        squares_(squares) {}
  void Add(const Eigen::Ref<const Eigen::VectorXd>& row) {
    for (int c : used_) means_[c].Add(row(c));
    if (robust_ >= 0) output_.push_back(row(robust_));
    if (squares_ != nullptr) squares_->Add(row);
  }
  // The offsets of the rows added, by column (zero for the columns not used), for rows of `size` columns.
  Eigen::VectorXd Offsets(const std::string& path, const std::vector<std::string>& names, int size) const {
    Eigen::VectorXd offset = Eigen::VectorXd::Zero(size);
    for (int c : used_) offset(c) = means_[c].Get(path, names[c]);
    if (robust_ >= 0)
      offset(robust_) =
          RobustOffset(Eigen::Map<const Eigen::VectorXd>(output_.data(), std::ssize(output_)), path, names[robust_]);
    return offset;
  }

 private:
  std::vector<int> used_;
  int robust_;
  std::vector<RunningMean> means_;
  std::vector<double> output_;
  ShiftedMeanSquares* squares_;
};

// The layout of a record of `rows` rows and `columns` columns: its split, checked (Split's InvalidArgument).
CsvLayout LayOutRows(const std::string& path, const DataSource& source, const FitOptions& options, long rows,
                     int columns);

// Detrending offsets of a CSV file: the estimation-part means of the used columns (DetrendSums), zero with
// Detrend::kNone. With `squares` (Detrend::kMean only) the same rows go to it too. `filled`: the time gaps to
// fill (ScanCsvTime), or null.
Eigen::VectorXd DetrendOffsets(const std::string& path, const io::CsvOptions& csv, const DataSource& source,
                               const FitOptions& options, const CsvLayout& layout, const TimeCheck* filled,
                               ShiftedMeanSquares* squares = nullptr);

// Runs f(); if it throws InvalidArgument, a bad row later in the file is the real problem (e.g. a ragged
// row makes the record look too short): report the data error first, as reading the whole table up
// front would.
template <class F>
auto DataErrorsFirst(const std::string& path, const io::CsvOptions& csv, F&& f) {
  try {
    return f();
  } catch (const InvalidArgument&) {
    io::CsvReadAhead reader(path, csv);
    Eigen::VectorXd row(reader.num_columns());
    while (reader.Next(row)) {}
    throw;
  }
}

}  // namespace ident::workflow::internal
