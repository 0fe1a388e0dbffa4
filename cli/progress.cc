#include "cli/progress.h"

#include <unistd.h>

#include <cstdio>
#include <utility>

#include <fmt/format.h>

namespace ident::cli {

Progress::Progress(std::string command)
    : command_(std::move(command)), start_(std::chrono::steady_clock::now()), terminal_(isatty(STDERR_FILENO)) {}

Progress::~Progress() {
  if (open_line_) std::fputc('\n', stderr);
}

void Progress::Report(long done, long total, const char* unit, int pass) {
  if (pass != pass_ || unit_ != unit) {
    pass_ = pass;
    unit_ = unit;
    reported_ = 0;
  }
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

}  // namespace ident::cli
