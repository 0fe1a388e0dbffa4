#include "ident/workflow/spike_robust_mean.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace ident::workflow {

namespace {

constexpr int kHalfWindow = 2;
constexpr double kMadToStd = 1.4826;

// Median of the finite y(t−2) … y(t+2) (y(t) itself is finite).
double LocalMedian(const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Index t) {
  double window[2 * kHalfWindow + 1];
  int n = 0;
  const Eigen::Index first = std::max<Eigen::Index>(0, t - kHalfWindow);
  const Eigen::Index last = std::min<Eigen::Index>(y.size() - 1, t + kHalfWindow);
  for (Eigen::Index s = first; s <= last; ++s)
    if (std::isfinite(y(s))) window[n++] = y(s);
  std::sort(window, window + n);
  return n % 2 == 1 ? window[n / 2] : 0.5 * (window[n / 2 - 1] + window[n / 2]);
}

}  // namespace

double SpikeRobustMean(const Eigen::Ref<const Eigen::VectorXd>& y) {
  std::vector<Eigen::Index> rows;
  std::vector<double> local;
  rows.reserve(static_cast<std::size_t>(y.size()));
  local.reserve(static_cast<std::size_t>(y.size()));
  for (Eigen::Index t = 0; t < y.size(); ++t) {
    if (!std::isfinite(y(t))) continue;
    rows.push_back(t);
    local.push_back(LocalMedian(y, t));
  }
  if (rows.empty()) return 0;
  // The scale of the nonzero deviations: exact zeros (a quantised signal on a plateau, where the median
  // reproduces it) carry no scale, and would make the MAD 0 on records with more than half of them.
  std::vector<double> deviation;
  deviation.reserve(rows.size());
  for (std::size_t i = 0; i < rows.size(); ++i)
    if (const double d = std::abs(y(rows[i]) - local[i]); d > 0) deviation.push_back(d);
  double limit = std::numeric_limits<double>::infinity();  // no deviation at all: nothing to replace
  if (!deviation.empty()) {
    const auto middle = deviation.begin() + static_cast<std::ptrdiff_t>(deviation.size() / 2);
    std::nth_element(deviation.begin(), middle, deviation.end());
    limit = kSpikeThreshold * kMadToStd * *middle;
  }
  // m ← m + (v − m)/k, as the plain mean of the workflow: exact for a constant column even near 1e308.
  double mean = 0;
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const double v = y(rows[i]);
    const double kept = std::abs(v - local[i]) > limit ? local[i] : v;
    mean += (kept - mean) / static_cast<double>(i + 1);
  }
  return mean;
}

}  // namespace ident::workflow
