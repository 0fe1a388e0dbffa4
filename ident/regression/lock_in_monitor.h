// LockInMonitor: a diagnostic that flags a robust estimator locked into a wrong mode.
//
// A robust regression estimator gives every sample a weight; for the Kárný–Hangos estimators the
// normalised weight νβ(t) ≈ (k+1)/(k + ê²/D_y) (spec §7a) is O(1) for a sample the model explains and
// ≈ 0 for an outlier. Outliers are by definition a minority: if more than half of the last M samples get
// νβ < threshold (i.e. the median weight over the window is below it), the estimator no longer describes
// most of the data. On ARX data with a binary input this is the signature of the Cauchy estimator's
// lock-in (docs/explanation/karny-hangos-estimator.md): a wrong Θ̂ that fits one half of the samples with a small scale D_y.
//
// O(1) per sample (a ring of M flags and a running count), allocation-free after construction.
//
// Example:
//   ident::LockInMonitor monitor(/*window=*/100, /*threshold=*/0.3);
//   ident::StepReport r = est.Update(y, z);
//   if (r.updated() && monitor.Add(r.nu * r.weight)) { /* locked in: restart, warn, ... */ }
#pragma once

#include <vector>

#include "common/error.h"

namespace ident {

class LockInMonitor {
 public:
  // Throws InvalidArgument unless window >= 2 and threshold > 0.
  LockInMonitor(int window, double threshold) : low_(window > 0 ? window : 0), threshold_(threshold) {
    IDENT_REQUIRE(window >= 2, "lock-in window = {}; need at least 2 samples", window);
    IDENT_REQUIRE(threshold > 0, "lock-in threshold = {}; need a positive weight nu*beta", threshold);
  }

  // Adds the normalised weight νβ of one updated sample (NaN counts as low). Returns flagged().
  bool Add(double nu_beta) noexcept {
    const bool low = !(nu_beta >= threshold_);
    if (count_ == window())
      num_low_ -= low_[next_];
    else
      ++count_;
    low_[next_] = low;
    num_low_ += low;
    next_ = next_ + 1 == window() ? 0 : next_ + 1;
    return flagged();
  }

  // True when the window is full and more than half of it has νβ < threshold.
  bool flagged() const noexcept { return count_ == window() && 2 * num_low_ > count_; }
  // Fraction of low-weight samples among those in the window (0 if empty).
  double low_fraction() const noexcept { return count_ ? static_cast<double>(num_low_) / count_ : 0.0; }
  int window() const noexcept { return static_cast<int>(low_.size()); }
  double threshold() const noexcept { return threshold_; }
  void Clear() noexcept { count_ = num_low_ = next_ = 0; }

 private:
  std::vector<char> low_;
  double threshold_;
  int count_ = 0, num_low_ = 0, next_ = 0;
};

}  // namespace ident
