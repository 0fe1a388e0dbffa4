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
  std::sort(window, window + n);
  return n % 2 == 1 ? window[n / 2] : 0.5 * (window[n / 2 - 1] + window[n / 2]);
}

// The deviation limit kSpikeThreshold·S of the header, from the first pass's deviations; +∞ when every
// finite sample equals its local median.
double DeviationLimit(const Eigen::VectorXd& y) {
  std::vector<double> deviation;
  for (Eigen::Index t = 0; t < y.size(); ++t)
    if (std::isfinite(y(t)))
      if (const double d = std::abs(y(t) - LocalMedian(y, t)); d > 0) deviation.push_back(d);
  if (deviation.empty()) return std::numeric_limits<double>::infinity();
  const auto middle = deviation.begin() + static_cast<std::ptrdiff_t>(deviation.size() / 2);
  std::nth_element(deviation.begin(), middle, deviation.end());
  return kSpikeThreshold * kMadToStd * *middle;
}

}  // namespace

double SpikeRobustMean(const Eigen::Ref<const Eigen::VectorXd>& y) {
  const Eigen::VectorXd measured = y;
  const double limit = DeviationLimit(measured);
  // Flagged samples leave the windows (NaN in w) and the rest are judged again, until no new one is
  // flagged: a cluster of spikes that fills half a window hides from the first median, not from the
  // medians once its edges are out.
  Eigen::VectorXd w = measured;
  for (int round = 0; round < kMaxRounds; ++round) {
    std::vector<Eigen::Index> flagged;
    for (Eigen::Index t = 0; t < w.size(); ++t)
      if (std::isfinite(w(t)) && std::abs(w(t) - LocalMedian(w, t)) > limit) flagged.push_back(t);
    if (flagged.empty()) break;
    for (Eigen::Index t : flagged) w(t) = std::numeric_limits<double>::quiet_NaN();
  }
  // m ← m + (v − m)/k, as the plain mean of the workflow: exact for a constant column even near 1e308. A
  // flagged sample counts as the median of its window's kept samples (none: it is left out).
  double mean = 0;
  long count = 0;
  for (Eigen::Index t = 0; t < measured.size(); ++t) {
    if (!std::isfinite(measured(t))) continue;
    const double kept = std::isfinite(w(t)) ? w(t) : LocalMedian(w, t);
    if (std::isnan(kept)) continue;
    mean += (kept - mean) / static_cast<double>(++count);
  }
  return mean;
}

}  // namespace ident::workflow
