#include "cli/time_gaps.h"

#include <string>

#include <fmt/format.h>

namespace ident::cli {

void PrintTimeGaps(std::FILE* out, const workflow::TimeCheck& time, bool filled) {
  constexpr std::size_t kShownGaps = 5;
  if (time.gaps.empty()) return;
  long missing = 0;
  for (const workflow::TimeGap& g : time.gaps) missing += g.missing;
  std::string shown;
  for (std::size_t i = 0; i < time.gaps.size() && i < kShownGaps; ++i) {
    const workflow::TimeGap& g = time.gaps[i];
    shown += fmt::format("{}row {} ({} -> {})", i ? ", " : "", g.row, g.t_before, g.t_after);
  }
  if (time.gaps.size() > kShownGaps) shown += ", ...";
  fmt::print(out, "time column '{}': {} gap{} (steps above {} x the median step {:.6g}; {} samples missing{}): {}\n",
             time.column, time.gaps.size(), time.gaps.size() == 1 ? "" : "s", workflow::kTimeGapFactor,
             time.median_step, missing,
             filled ? ", filled as missing samples" : "; --missing fills them as missing samples", shown);
}

}  // namespace ident::cli
