#include "models/output_cleaner.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "common/error.h"

namespace ident::models {

std::string OutputCleaningOptions::Validate() const {
  if (!(std::isfinite(clip) && clip > 0)) return fmt::format("cleaning clip = {}; need clip > 0", clip);
  if (!(std::isfinite(screen) && screen >= 0)) return fmt::format("cleaning screen = {}; need screen >= 0", screen);
  if (!(std::isfinite(gross) && gross >= 0)) return fmt::format("cleaning gross = {}; need gross >= 0", gross);
  if (max_run < 1) return fmt::format("cleaning max_run = {}; need max_run >= 1", max_run);
  if (warm_up < 0) return fmt::format("cleaning warm_up = {}; need warm_up >= 0", warm_up);
  return "";
}

OutputCleaner::OutputCleaner(const OutputCleaningOptions& options) : options_(options) {
  const std::string error = options_.Validate();
  IDENT_REQUIRE(error.empty(), "{}", error);
  warm_up_end_ = options_.warm_up;
}

void OutputCleaner::Reset() {
  seen_ = cleaned_ = 0;
  warm_up_end_ = options_.warm_up;
  run_ = 0;
  y_min_ = y_max_ = 0;
  have_range_ = false;
  last_ = 0;
  num_differences_ = next_difference_ = 0;
  num_errors_ = next_error_ = 0;
}

void OutputCleaner::Restore(double y) {
  if (cleaned_ == 0 || !std::isfinite(y)) return;
  --cleaned_;
  run_ = 0;
  if (num_differences_ > 0) differences_[(next_difference_ + kDifferences - 1) % kDifferences] += y - last_;
  last_ = y;
  y_min_ = std::min(y_min_, y);
  y_max_ = std::max(y_max_, y);
}

double OutputCleaner::Store(double y) {
  if (std::isfinite(y)) {
    if (have_range_) {
      differences_[next_difference_] = y - last_;
      next_difference_ = (next_difference_ + 1) % kDifferences;
      num_differences_ = std::min(num_differences_ + 1, kDifferences);
    }
    last_ = y;
  }
  return y;
}

double OutputCleaner::Accept(double y) {
  run_ = 0;
  if (std::isfinite(y)) {
    y_min_ = have_range_ ? std::min(y_min_, y) : y;
    y_max_ = have_range_ ? std::max(y_max_, y) : y;
    Store(y);
    have_range_ = true;
  }
  return y;
}

double OutputCleaner::RingScale(const double* ring, int count) {
  if (count < 5) return std::numeric_limits<double>::quiet_NaN();
  // The median of the nonzero entries: exact zeros (a quantised or constant stretch, a model that
  // reproduces it) carry no scale, and more than half of them would make the MAD 0 and switch the test off.
  double work[kDifferences];
  int nonzero = 0;
  for (int i = 0; i < count; ++i)
    if (ring[i] != 0) work[nonzero++] = std::abs(ring[i]);
  if (nonzero == 0) return 0;
  std::nth_element(work, work + nonzero / 2, work + nonzero);
  return 1.4826 * work[nonzero / 2];
}

bool OutputCleaner::IsGross(double e) const {
  const double scale = ErrorScale();
  return options_.gross > 0 && !std::isnan(scale) && std::abs(e) > options_.gross * scale;
}

double OutputCleaner::DifferenceScale() const { return RingScale(differences_, num_differences_); }
double OutputCleaner::ErrorScale() const { return RingScale(errors_, num_errors_); }

double OutputCleaner::Clean(double y, double y_hat, double scale, bool flagged, bool judged) {
  const long t = seen_++;
  if (!options_.enabled || !judged || !have_range_ || run_ >= options_.max_run || !std::isfinite(y)) return Accept(y);
  if (t < warm_up_end_) {  // (4): the model-free screen
    // s = 0: every recent difference is exactly zero, and any jump is gross against them.
    const double s = DifferenceScale();
    if (!(options_.screen > 0 && !std::isnan(s) && std::abs(y - last_) > options_.screen * s)) return Accept(y);
    y_hat = last_;
    scale = s;
  } else {
    if (!std::isfinite(y_hat)) return Accept(y);
    const double known = ErrorScale();
    const double gross_scale = std::isnan(known) ? 0 : known;  // fewer than 5 errors: every flagged one
    errors_[next_error_] = y - y_hat;
    next_error_ = (next_error_ + 1) % kDifferences;
    num_errors_ = std::min(num_errors_ + 1, kDifferences);
    // Only the Huber clip (gross = 0) needs the estimator's scale; a gross error is judged by the errors'.
    if (!flagged || (options_.gross == 0 && !(std::isfinite(scale) && scale > 0)) ||
        (options_.gross > 0 && !(std::abs(y - y_hat) > options_.gross * gross_scale)))
      return Accept(y);
  }
  // (1): an error cleaned as gross (the warm-up screen, or (5) with gross > 0) is no evidence of y beyond
  // ŷ (ψ redescends to 0); with gross = 0 every flagged error is clipped (Huber ψ).
  const bool redescend = t < warm_up_end_ || options_.gross > 0;  // the error was cleaned as gross
  const double bound = options_.clip * scale;
  const double cleaned = redescend ? y_hat : y_hat + std::clamp(y - y_hat, -bound, bound);
  ++run_;
  ++cleaned_;
  return Store(std::clamp(cleaned, y_min_, y_max_));  // (2)
}

}  // namespace ident::models
