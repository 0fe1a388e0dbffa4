#include "ident/workflow/time_column.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "common/error.h"

namespace ident::workflow {

int TimeColumnIndex(const std::vector<std::string>& names, const std::vector<int>& used_columns) {
  for (const char* name : {"t", "time"}) {
    const auto it = std::find(names.begin(), names.end(), name);
    if (it != names.end()) {
      const int column = static_cast<int>(it - names.begin());
      return std::find(used_columns.begin(), used_columns.end(), column) != used_columns.end() ? -1 : column;
    }
  }
  return -1;
}

std::optional<TimeGap> ArrivingTimeCheck::Next(double t, long row, const std::string& column, const std::string& source,
                                               long line) {
  const auto where = [&] { return line < 0 ? source : fmt::format("{}:{}", source, line); };
  if (std::isnan(t)) return std::nullopt;  // a missing sample, passed over as CheckTimeColumn does
  if (!started_) {
    started_ = true;
    previous_ = t;
    taken_ = 1;
    return std::nullopt;
  }
  if (!(t > previous_))
    throw DataError(fmt::format("{}: time column '{}' does not increase: {} after {}", where(), column, t, previous_));
  const double step = t - previous_;
  // The median of the window is at least its smallest step, and min_ at most that: a step up to
  // kTimeGapFactor times min_ is regular without the median (the common case). Past it, min_ is brought
  // up to the window's smallest step, and the median is sorted out only when that does not decide.
  double median = 0;
  if (count_ > 0 && step > kTimeGapFactor * min_) min_ = WindowMin();
  if (count_ > 0 && step > kTimeGapFactor * min_ && step > kTimeGapFactor * (median = median_step())) {
    const double samples = std::round(step / median);
    if (!(samples - 1 <= static_cast<double>(taken_)))
      throw DataError(fmt::format(
          "{}: time column '{}' jumps from {} to {}: the gap misses more samples than the {} rows before it; cut the "
          "record at its gaps",
          where(), column, previous_, t, taken_));
    const TimeGap gap{.row = static_cast<int>(std::min<long>(row, std::numeric_limits<int>::max())),
                      .t_before = previous_,
                      .t_after = t,
                      .missing = std::max(1L, static_cast<long>(samples) - 1),
                      .filled = 0,
                      .step = median};
    previous_ = t;
    ++taken_;
    return gap;
  }
  // A regular step: into the window of the last kSteps (a ring; the oldest leaves it).
  steps_[static_cast<std::size_t>(count_ % kSteps)] = step;
  ++count_;
  if (count_ == 2 * kSteps) count_ = kSteps;  // keeps the index cycling without overflow
  min_ = std::min(min_, step);                // still at most the window's smallest when an older smallest has left
  previous_ = t;
  ++taken_;
  return std::nullopt;
}

double ArrivingTimeCheck::WindowMin() const {
  const int held = std::min(count_, kSteps);
  return *std::min_element(steps_.begin(), steps_.begin() + held);
}

double ArrivingTimeCheck::median_step() const {
  const int held = std::min(count_, kSteps);
  if (held == 0) return 0;
  std::array<double, kSteps> sorted = steps_;
  std::sort(sorted.begin(), sorted.begin() + held);
  return held % 2 ? sorted[static_cast<std::size_t>(held / 2)]
                  : (sorted[static_cast<std::size_t>(held / 2 - 1)] + sorted[static_cast<std::size_t>(held / 2)]) / 2;
}

std::optional<TimeCheck> CheckTimeColumn(const io::DataTable& table, const std::vector<int>& used_columns) {
  const int column = TimeColumnIndex(table.names, used_columns);
  if (column < 0) return std::nullopt;
  TimeCheck check;
  check.column = table.names[static_cast<std::size_t>(column)];
  const auto t = table.values.col(column);
  // Steps between consecutive recorded times (rows with a NaN time passed over).
  std::vector<double> steps;
  steps.reserve(static_cast<std::size_t>(std::max<Eigen::Index>(t.size() - 1, 0)));
  int previous = -1;
  for (int i = 0; i < t.size(); ++i) {
    if (std::isnan(t(i))) continue;
    if (previous >= 0) {
      if (!(t(i) > t(previous))) {
        const long line = table.Line(i);
        throw DataError(fmt::format("{}{}: time column '{}' does not increase: {} after {}{}", table.source,
                                    line > 0 ? fmt::format(":{}", line) : "", check.column, t(i), t(previous),
                                    line > 0 ? "" : fmt::format(" (row {})", i + 1)));
      }
      steps.push_back(t(i) - t(previous));
    }
    previous = i;
  }
  if (steps.empty()) return check;
  std::vector<double> sorted = steps;
  const auto middle = sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() / 2);
  std::nth_element(sorted.begin(), middle, sorted.end());
  double median = *middle;
  if (sorted.size() % 2 == 0) median = (median + *std::max_element(sorted.begin(), middle)) / 2;
  check.median_step = median;
  previous = -1;
  for (int i = 0; i < t.size(); ++i) {
    if (std::isnan(t(i))) continue;
    if (previous >= 0 && t(i) - t(previous) > kTimeGapFactor * median) {
      const double samples = std::round((t(i) - t(previous)) / median);
      const long missing = samples - 1 >= static_cast<double>(std::numeric_limits<long>::max() / 2)
                               ? std::numeric_limits<long>::max() / 2
                               : std::max(1L, static_cast<long>(samples) - 1);
      check.gaps.push_back({i + 1, t(previous), t(i), missing, 0, median});
    }
    previous = i;
  }
  return check;
}

io::DataTable FillTimeGaps(const io::DataTable& table, TimeCheck& check) {
  if (check.gaps.empty()) return table;
  const int column = table.ColumnIndex(check.column);
  long inserted = 0;
  for (const TimeGap& g : check.gaps) {
    inserted += g.missing;
    if (inserted > table.num_rows()) {
      const long line = table.Line(g.row - 1);
      throw DataError(fmt::format(
          "{}{}: time column '{}' jumps from {} to {}: the gaps miss more samples than the record holds ({} rows); "
          "cut the record at its gaps",
          table.source, line > 0 ? fmt::format(":{}", line) : "", check.column, g.t_before, g.t_after,
          table.num_rows()));
    }
  }
  io::DataTable out;
  out.source = table.source;
  out.names = table.names;
  out.generated_names = table.generated_names;
  const Eigen::Index cols = table.values.cols();
  out.values.resize(table.values.rows() + inserted, cols);
  Eigen::Index to = 0, from = 0;
  auto copy_until = [&](Eigen::Index end) {  // rows [from, end) of the table
    const Eigen::Index n = end - from;
    out.values.middleRows(to, n) = table.values.middleRows(from, n);
    to += n;
    from = end;
  };
  for (TimeGap& g : check.gaps) {
    copy_until(g.row - 1);
    for (long k = 1; k <= g.missing; ++k, ++to) {
      out.values.row(to).setConstant(std::numeric_limits<double>::quiet_NaN());
      out.values(to, column) = g.t_before + static_cast<double>(k) * check.median_step;
    }
    g.filled = g.missing;
  }
  copy_until(table.values.rows());
  return out;
}

std::optional<TimeCheck> CheckRecordTime(io::DataTable& table, const std::vector<int>& used_columns, bool fill) {
  std::optional<TimeCheck> time = CheckTimeColumn(table, used_columns);
  if (time && fill && !time->gaps.empty()) table = FillTimeGaps(table, *time);
  return time;
}

nlohmann::ordered_json TimeGapsJson(const std::optional<TimeCheck>& time) {
  if (!time) return nullptr;
  nlohmann::ordered_json gaps = nlohmann::ordered_json::array();
  for (const TimeGap& g : time->gaps)
    gaps.push_back({{"row", g.row},
                    {"t_before", g.t_before},
                    {"t_after", g.t_after},
                    {"missing", g.missing},
                    {"filled", g.filled}});
  return gaps;
}

}  // namespace ident::workflow
