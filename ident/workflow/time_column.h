// The record's time column: a column named "t" (or else "time") that the model does not read. Its
// values must increase; a step longer than 1.5 times the median step is a gap (samples not recorded).
// With missing samples allowed (--missing) each gap is filled with its missing rows, NaN in every
// column but the time column, so that no regressor straddles a gap: a regressor holding a NaN is not
// used (workflow/fit.h), and the time axis keeps its sampling interval.
//
//   CheckTimeColumn   finds the column, checks it increases, lists its gaps
//   FillTimeGaps      inserts each gap's missing rows
//   CheckRecordTime   both, as the commands that read a record in memory do
//   TimeGapsJson      the reports' `time_gaps` key
//   ArrivingTimeCheck the check row by row as rows arrive (ident stream), in constant memory
#pragma once

#include <array>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "ident/io/csv.h"

namespace ident::workflow {

struct TimeGap {
  int row = 0;  // 1-based data row of the record that ends the gap (t_after's)
  double t_before = 0, t_after = 0;
  long missing = 0;  // samples missing in it: round(step / median step) - 1, at least 1
  long filled = 0;   // rows FillTimeGaps inserted for it
  double step = 0;   // the spacing of its missing rows' times: the median step it was judged by
};

struct TimeCheck {
  std::string column;
  double median_step = 0;
  std::vector<TimeGap> gaps;
};

// A step longer than this many median steps is a gap.
inline constexpr double kTimeGapFactor = 1.5;

// Null if the table has no time column or the model reads it (`used_columns`). Rows whose time is NaN
// (a missing sample) are passed over. Throws DataError
// "<source>:<line>: time column 't' does not increase: 4 after 5".
std::optional<TimeCheck> CheckTimeColumn(const io::DataTable& table, const std::vector<int>& used_columns);

// Inserts each gap's missing rows (time t_before + k * median step, NaN elsewhere), setting
// TimeGap::filled. Throws DataError when the gaps hold more missing rows than the record has rows.
io::DataTable FillTimeGaps(const io::DataTable& table, TimeCheck& check);

// The time column's index in `names` ("t", else "time"), or -1 when there is none or the model reads it.
int TimeColumnIndex(const std::vector<std::string>& names, const std::vector<int>& used_columns);

// The time column of rows that arrive one at a time: the whole record's median step is not known, so a
// step is compared with the median of the last kSteps regular steps (all of them while fewer have arrived;
// the first step has none and is never a gap). Its values must increase, as in CheckTimeColumn.
class ArrivingTimeCheck {
 public:
  static constexpr int kSteps = 21;
  // The gap that ends at time `t` of 1-based data row `row` (TimeGap::missing = round(step / median) − 1,
  // at least 1), or null. Throws DataError "<where>: time column 't' does not increase: 4 after 5" (`where`:
  // "source:line"), and for a gap that misses more samples than rows have arrived before it.
  std::optional<TimeGap> Next(double t, long row, const std::string& column, const std::string& where) {
    return Next(t, row, column, where, -1);
  }
  // The same, `where` given as a source and its 1-based line ("source:line"), formatted only for an error.
  std::optional<TimeGap> Next(double t, long row, const std::string& column, const std::string& source, long line);
  // The median of the last kSteps regular steps (0 before the first).
  double median_step() const;

 private:
  std::array<double, kSteps> steps_{};  // in arrival order (a ring)
  int count_ = 0;                       // steps held (up to kSteps); the next goes to steps_[count_ % kSteps] once full
  long taken_ = 0;
  double previous_ = 0;
  // At most the smallest step held (none: +inf): lowered by each step, brought up to it by WindowMin()
  // only when a step exceeds kTimeGapFactor times it.
  double min_ = std::numeric_limits<double>::infinity();
  double WindowMin() const;  // the smallest step held (count_ > 0)
  bool started_ = false;
};

// CheckTimeColumn, then, when `fill` (--missing) and there are gaps, FillTimeGaps in place.
std::optional<TimeCheck> CheckRecordTime(io::DataTable& table, const std::vector<int>& used_columns, bool fill);

// [{row, t_before, t_after, missing, filled}], or null when no time column was checked (`time` null).
nlohmann::ordered_json TimeGapsJson(const std::optional<TimeCheck>& time);

}  // namespace ident::workflow
