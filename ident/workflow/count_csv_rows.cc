// The row count of ident/workflow/fit.h: CountCsvDataRows, line by line, or a block's lines at once where
// the block allows.
#include <bit>
#include <cerrno>
#include <cstdint>
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

// The LFs in [p, end) and whether two of them are adjacent (an empty line between), eight bytes at a time.
struct LineFeeds {
  long count = 0;
  bool adjacent = false;
};
LineFeeds CountLineFeeds(const char* p, const char* const end) {
  LineFeeds out;
  bool previous = false;  // the byte before p is an LF
  if constexpr (std::endian::native == std::endian::little) {
    constexpr std::uint64_t kOnes = 0x0101010101010101, kLow = kOnes * 0x7F, kHigh = kOnes * 0x80;
    constexpr std::uint64_t kLf = kOnes * '\n';
    std::uint64_t carry = 0;  // bit 7 set: the last byte of the previous word is an LF
    for (; end - p >= 8; p += 8) {
      std::uint64_t word;
      std::memcpy(&word, p, 8);
      const std::uint64_t x = word ^ kLf;                           // 0 bytes where the LFs are
      const std::uint64_t lf = ~(((x & kLow) + kLow) | x) & kHigh;  // bit 7 of each byte that is 0, exactly
      out.count += std::popcount(lf);
      out.adjacent |= (((lf << 8) | carry) & lf) != 0;
      carry = lf >> 56;
    }
    previous = carry != 0;
  }
  for (; p < end; ++p) {
    const bool lf = *p == '\n';
    out.count += lf;
    out.adjacent |= previous && lf;
    previous = lf;
  }
  return out;
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
