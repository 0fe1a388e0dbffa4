#include "ident/workflow/spike_robust_mean.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace ident::workflow {

namespace {

constexpr int kHalfWindow = 4;
constexpr double kMadToStd = 1.4826;
constexpr int kMaxRounds = 20;  // rounds of flagging; each removes the outer layer of a cluster

// Median of the finite w(t−4) … w(t+4); NaN if there is none.
double LocalMedian(const Eigen::VectorXd& w, Eigen::Index t) {
  double window[2 * kHalfWindow + 1];
  int n = 0;
  const Eigen::Index first = std::max<Eigen::Index>(0, t - kHalfWindow);
  const Eigen::Index last = std::min<Eigen::Index>(w.size() - 1, t + kHalfWindow);
  for (Eigen::Index s = first; s <= last; ++s)
    if (std::isfinite(w(s))) window[n++] = w(s);
  if (n == 0) return std::numeric_limits<double>::quiet_NaN();
  double* const middle = window + n / 2;
  std::nth_element(window, middle, window + n);
  if (n % 2 == 1) return *middle;
  return 0.5 * (*std::max_element(window, middle) + *middle);  // the two middle values of an even count
}

// The deviation limit kSpikeThreshold·S of the header from y and its local medians r; +∞ when every
// finite sample equals its local median.
double DeviationLimit(const Eigen::VectorXd& y, const Eigen::VectorXd& r) {
  std::vector<double> deviation;
  for (Eigen::Index t = 0; t < y.size(); ++t)
    if (const double d = std::abs(y(t) - r(t)); d > 0) deviation.push_back(d);  // NaN: not > 0
  if (deviation.empty()) return std::numeric_limits<double>::infinity();
  const auto middle = deviation.begin() + static_cast<std::ptrdiff_t>(deviation.size() / 2);
  std::nth_element(deviation.begin(), middle, deviation.end());
  return kSpikeThreshold * kMadToStd * *middle;
}

}  // namespace

double SpikeRobustMean(const Eigen::Ref<const Eigen::VectorXd>& y) {
  // w: y with the flagged samples NaN; r: the local medians of w at its finite samples.
  Eigen::VectorXd w = y, r(y.size());
  const auto medians = [&] {
    for (Eigen::Index t = 0; t < w.size(); ++t)
      r(t) = std::isfinite(w(t)) ? LocalMedian(w, t) : std::numeric_limits<double>::quiet_NaN();
  };
  medians();
  const double limit = DeviationLimit(w, r);
  // Flagged samples leave the windows and the rest are judged again, until no new one is flagged: a
  // cluster of spikes that fills half a window hides from the first median, not from the medians once
  // its edges are out.
  for (int round = 0; round < kMaxRounds; ++round) {
    bool any = false;
    for (Eigen::Index t = 0; t < w.size(); ++t)
      if (std::abs(w(t) - r(t)) > limit) {  // NaN (flagged or missing): false
        w(t) = std::numeric_limits<double>::quiet_NaN();
        any = true;
      }
    if (!any) break;
    medians();
  }
  // m ← m + (v − m)/k, as the plain mean of the workflow: exact for a constant column even near 1e308. A
  // flagged sample counts as the median of its window's kept samples (none: it is left out).
  double mean = 0;
  long count = 0;
  for (Eigen::Index t = 0; t < y.size(); ++t) {
    if (!std::isfinite(y(t))) continue;
    const double kept = std::isfinite(w(t)) ? w(t) : LocalMedian(w, t);
    if (std::isnan(kept)) continue;
    mean += (kept - mean) / static_cast<double>(++count);
  }
  return mean;
}

}  // namespace ident::workflow
