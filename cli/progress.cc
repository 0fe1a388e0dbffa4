#include "cli/progress.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <utility>

#include <fmt/format.h>

#include "ident/io/csv.h"
#include "ident/io/mat_file.h"

namespace ident::cli {

Progress::Progress(std::string command)
    : command_(std::move(command)), start_(std::chrono::steady_clock::now()), terminal_(isatty(STDERR_FILENO)) {}

Progress::~Progress() {
  if (open_line_) std::fputc('\n', stderr);
}

void Progress::Report(long done, long total, const char* unit, int pass) {
  if (pass != pass_ || (unit != unit_pointer_ && unit_ != unit)) {
    pass_ = pass;
    unit_ = unit;
    reported_ = 0;
  }
  unit_pointer_ = unit;
  const int tenth = total > 0 ? static_cast<int>(10 * done / total) : 10;
  if (tenth <= reported_) return;
  reported_ = tenth;
  if (std::chrono::steady_clock::now() - start_ < std::chrono::seconds(2)) return;
  const long percent = total > 0 ? 100 * done / total : 100;
  const std::string stage = pass > 0 ? fmt::format("pass {}: ", pass) : "";
  const std::string line = fmt::format("ident {}: {}{} % ({} of {} {})", command_, stage, percent, done, total, unit);
  if (terminal_) {
    fmt::print(stderr, "\r{:<72}{}", line, tenth == 10 ? "\n" : "");
    open_line_ = tenth < 10;
  } else {
    fmt::print(stderr, "{}\n", line);
  }
  std::fflush(stderr);
}

std::function<void(long)> ReadingProgress(Progress& progress, const std::string& path) {
  std::error_code error;
  if (!io::CanReadTwice(path) || io::IsMatFile(path)) return {};
  const std::uintmax_t size = std::filesystem::file_size(path, error);
  if (error || size == 0) return {};
  constexpr long kMegabyte = 1 << 20;
  const long total = static_cast<long>((size + kMegabyte - 1) / kMegabyte);
  return [&progress, total](long bytes) { progress.Report(bytes / kMegabyte, total, "MB read"); };
}

std::function<void(int, double)> DecadesProgress(Progress& progress, double tolerance, const char* unit) {
  return [&progress, tolerance, unit, first = 0.0, total = 1L](int iteration, double measure) mutable {
    if (iteration == 0) {
      first = measure;
      const double decades = std::log10(first / tolerance);  // NaN or ±inf for a measure that is not finite
      total = std::isfinite(decades) ? std::clamp(static_cast<long>(std::ceil(decades)), 1L, 1000L) : 1L;
    }
    const double fallen = std::log10(first / measure);
    const long done = measure <= tolerance ? total
                      : std::isfinite(fallen)
                          ? std::clamp(static_cast<long>(std::clamp(fallen, 0.0, 1e3)), 0L, total - 1)
                          : 0L;
    progress.Report(done, total, unit);
  };
}

}  // namespace ident::cli
