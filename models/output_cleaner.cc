#include "models/output_cleaner.h"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "ident/common/error.h"

namespace ident::models {

std::string OutputCleaningOptions::Validate() const {
  if (!(std::isfinite(clip) && clip > 0)) return fmt::format("cleaning clip = {}; need clip > 0", clip);
  if (max_run < 1) return fmt::format("cleaning max_run = {}; need max_run >= 1", max_run);
  if (warm_up < 0) return fmt::format("cleaning warm_up = {}; need warm_up >= 0", warm_up);
  return "";
}

OutputCleaner::OutputCleaner(const OutputCleaningOptions& options) : options_(options) {
  const std::string error = options_.Validate();
  IDENT_REQUIRE(error.empty(), "{}", error);
}

void OutputCleaner::Reset() {
  seen_ = cleaned_ = 0;
  run_ = 0;
  y_min_ = y_max_ = 0;
  have_range_ = false;
}

double OutputCleaner::Accept(double y) {
  run_ = 0;
  if (std::isfinite(y)) {
    y_min_ = have_range_ ? std::min(y_min_, y) : y;
    y_max_ = have_range_ ? std::max(y_max_, y) : y;
    have_range_ = true;
  }
  return y;
}

double OutputCleaner::Clean(double y, double y_hat, double scale, bool flagged) {
  const long t = seen_++;
  if (!options_.enabled || !flagged || t < options_.warm_up || !have_range_ || run_ >= options_.max_run ||
      !std::isfinite(y) || !std::isfinite(y_hat) || !(std::isfinite(scale) && scale > 0))
    return Accept(y);
  const double bound = options_.clip * scale;
  const double cleaned = y_hat + std::clamp(y - y_hat, -bound, bound);  // (1)
  ++run_;
  ++cleaned_;
  return std::clamp(cleaned, y_min_, y_max_);  // (2)
}

}  // namespace ident::models
