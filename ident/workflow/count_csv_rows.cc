// The row count of ident/workflow/fit.h: CountCsvDataRows, line by line, or a block's lines at once where
// the block allows.
#include <cerrno>
#include <cstddef>
#include <cstring>
#include <fstream>
#include <string_view>
#include <vector>

#include <fmt/format.h>

#include "common/error.h"
#include "ident/io/csv.h"
#include "ident/workflow/fit.h"

namespace ident::workflow {
namespace {

// The LFs in [p, end) and whether two of them are adjacent (an empty line between): plain loops over the
// bytes, which the compiler vectorises, summing 255 bytes at a time in a byte.
struct LineFeeds {
  long count = 0;
  bool adjacent = false;
};
LineFeeds CountLineFeeds(const char* p, const char* const end) {
  const std::ptrdiff_t n = end - p;
  long count = 0;
  unsigned char adjacent = 0;
  std::ptrdiff_t i = 0;
  for (; i + 256 <= n; i += 255) {
    unsigned char sum = 0;
    for (int k = 0; k < 255; ++k) {
      const unsigned char here = p[i + k] == '\n', next = p[i + k + 1] == '\n';
      sum += here;
      adjacent |= here & next;
    }
    count += sum;
  }
  for (; i + 1 < n; ++i) {
    const unsigned char here = p[i] == '\n', next = p[i + 1] == '\n';
    count += here;
    adjacent |= here & next;
  }
  if (n > 0) count += p[n - 1] == '\n';
  return {count, adjacent != 0};
}

// The lines of [p, end) that end in an LF, counted at once when they are all data lines: p starts a line
// with a character other than ' ', '\t', LF, CR and '#', and up to the last LF there is no CR, '#',
// space, tab or empty line. Returns the last LF (and adds the lines to *lines), or null.
const char* CountPlainLines(const char* p, const char* const end, long* lines) {
  const std::size_t last = std::string_view(p, static_cast<std::size_t>(end - p)).rfind('\n');
  if (last == std::string_view::npos) return nullptr;
  const std::size_t size = last + 1;
  for (const char special : {'\r', '#', ' ', '\t'})
    if (std::memchr(p, special, size) != nullptr) return nullptr;
  const LineFeeds feeds = CountLineFeeds(p, p + size);
  if (feeds.adjacent) return nullptr;
  *lines += feeds.count;
  return p + last;
}

}  // namespace

long CountCsvDataRows(const std::string& path) {
  std::ifstream in(path, std::ios::in | std::ios::binary);
  if (!in) throw DataError(fmt::format("cannot open '{}': {}", path, std::strerror(errno)));
  io::internal::CountCsvFileOpened();
  // A line ends at LF or CR (CRLF: an empty line between them, not counted) and counts if it has a
  // character other than ' ' and '\t' and the first such is not '#' (the reader skips the others: blank
  // lines and comments). Past a line's first such character, memchr finds its end; a block whose lines
  // are all plain data lines is counted at once (CountPlainLines), tried once a block.
  std::vector<char> block(1 << 20);
  long lines = 0;
  enum { kBlank, kContent, kComment } state = kBlank;  // of the current line so far
  while (in) {
    in.read(block.data(), static_cast<std::streamsize>(block.size()));
    const char* p = block.data();
    const char* const end = p + in.gcount();
    const char* next_cr = nullptr;  // the first CR at or after p (end: none); null: not searched yet
    bool tried = false;             // CountPlainLines on this block
    while (p < end) {
      if (state == kBlank) {
        const char c = *p;
        if (c == ' ' || c == '\t' || c == '\n' || c == '\r') {
          ++p;
          continue;
        }
        if (c != '#' && !tried) {
          tried = true;
          if (const char* last = CountPlainLines(p, end, &lines)) {
            p = last + 1;
            continue;
          }
        }
        state = c == '#' ? kComment : kContent;
      }
      if (next_cr == nullptr || next_cr < p) {
        next_cr = static_cast<const char*>(std::memchr(p, '\r', static_cast<std::size_t>(end - p)));
        if (next_cr == nullptr) next_cr = end;
      }
      const char* lf = static_cast<const char*>(std::memchr(p, '\n', static_cast<std::size_t>(next_cr - p)));
      const char* const line_end = lf ? lf : next_cr;
      if (line_end == end) break;  // the line goes on in the next block
      lines += state == kContent;
      state = kBlank;
      p = line_end + 1;
    }
  }
  if (in.bad()) throw DataError(fmt::format("cannot read '{}': {}", path, std::strerror(errno)));
  lines += state == kContent;
  return lines > 0 ? lines - 1 : 0;  // minus the header
}

}  // namespace ident::workflow
