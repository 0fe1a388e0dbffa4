// The row count of ident/workflow/fit.h: CountCsvDataRows, line by line, or a block's lines at once where
// the block allows; a large file in two halves at once.
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstddef>
#include <cstring>
#include <exception>
#include <string_view>
#include <thread>
#include <vector>

#include <fmt/format.h>

#include "common/error.h"
#include "ident/io/csv.h"
#include "ident/workflow/fit.h"
#include "ident/workflow/internal/row_count.h"

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

// A line's state so far, as the count walks it.
enum class LineState { kBlank, kContent, kComment };

// The lines of bytes [begin, end) of `fd` as CountCsvDataRows counts them (begin starts a line: the file's
// start, or just after an LF), and the state of the last line if the range ends inside it. A line ends at LF
// or CR (CRLF: an empty line between them, not counted) and counts if it has a character other than ' ' and
// '\t' and the first such is not '#' (the reader skips the others: blank lines and comments). Past a line's
// first such character, memchr finds its end; a block whose lines are all plain data lines is counted at once
// (CountPlainLines), tried once a block. Throws DataError if the file cannot be read.
struct RangeCount {
  long lines = 0;
  LineState state = LineState::kBlank;
};
// With `end` < 0 the file is read with read(2) to its end (a pipe, a device) instead of at offsets.
RangeCount CountRange(int fd, long begin, const long end, const std::string& path) {
  std::vector<char> block(1 << 20);
  RangeCount count;
  LineState& state = count.state;
  while (end < 0 || begin < end) {
    const std::size_t want =
        static_cast<std::size_t>(end < 0 ? std::ssize(block) : std::min<long>(std::ssize(block), end - begin));
    const ssize_t got = end < 0 ? ::read(fd, block.data(), want) : ::pread(fd, block.data(), want, begin);
    if (got < 0 && errno == EINTR) continue;
    if (got < 0) throw DataError(fmt::format("cannot read '{}': {}", path, std::strerror(errno)));
    if (got == 0) break;  // the file is shorter than it was
    begin += got;
    const char* p = block.data();
    const char* const stop = p + got;
    const char* next_cr = nullptr;  // the first CR at or after p (stop: none); null: not searched yet
    bool tried = false;             // CountPlainLines on this block
    while (p < stop) {
      if (state == LineState::kBlank) {
        const char c = *p;
        if (c == ' ' || c == '\t' || c == '\n' || c == '\r') {
          ++p;
          continue;
        }
        if (c != '#' && !tried) {
          tried = true;
          if (const char* last = CountPlainLines(p, stop, &count.lines)) {
            p = last + 1;
            continue;
          }
        }
        state = c == '#' ? LineState::kComment : LineState::kContent;
      }
      if (next_cr == nullptr || next_cr < p) {
        next_cr = static_cast<const char*>(std::memchr(p, '\r', static_cast<std::size_t>(stop - p)));
        if (next_cr == nullptr) next_cr = stop;
      }
      const char* lf = static_cast<const char*>(std::memchr(p, '\n', static_cast<std::size_t>(next_cr - p)));
      const char* const line_end = lf ? lf : next_cr;
      if (line_end == stop) break;  // the line goes on in the next block
      count.lines += state == LineState::kContent;
      state = LineState::kBlank;
      p = line_end + 1;
    }
  }
  return count;
}

// Where a line starts at or past byte `at` of a file of `size` bytes: just after the first LF at or past `at`
// (the lines before it and from it count apart exactly what the whole counts); 0 for none within a line's length
// limit of `at`.
long LineStartFrom(int fd, long at, long size) {
  std::vector<char> window(1 << 16);
  for (const long from = at; at < size && at < from + static_cast<long>(io::kMaxCsvLineBytes);) {
    const ssize_t got =
        ::pread(fd, window.data(), static_cast<std::size_t>(std::min<long>(std::ssize(window), size - at)), at);
    if (got < 0 && errno == EINTR) continue;
    if (got <= 0) return 0;
    if (const void* lf = std::memchr(window.data(), '\n', static_cast<std::size_t>(got)))
      return at + (static_cast<const char*>(lf) - window.data()) + 1;
    at += got;
  }
  return 0;
}

// The file opened for reading (counted as an open of a CSV file), closed when it goes; its size if regular, else -1.
struct OpenFile {
  explicit OpenFile(const std::string& path) : fd(::open(path.c_str(), O_RDONLY | O_CLOEXEC)) {
    if (fd < 0) throw DataError(fmt::format("cannot open '{}': {}", path, std::strerror(errno)));
    io::internal::CountCsvFileOpened();
    struct stat info {};
    size = ::fstat(fd, &info) == 0 && S_ISREG(info.st_mode) ? static_cast<long>(info.st_size) : -1;
  }
  ~OpenFile() { ::close(fd); }
  OpenFile(const OpenFile&) = delete;
  OpenFile& operator=(const OpenFile&) = delete;
  int fd;
  long size;
};

}  // namespace

long CountCsvDataRows(const std::string& path) {
  return internal::CountCsvDataRows(path, internal::kTwoThreadRowCountBytes);
}

long internal::CountCsvDataRows(const std::string& path, long two_thread_bytes) {
  const OpenFile file(path);
  const int fd = file.fd;
  const long size = file.size;
  // A regular file of two_thread_bytes or more is counted in two halves at once; anything else in one go.
  const long cut = size >= two_thread_bytes ? LineStartFrom(fd, size / 2, size) : 0;
  RangeCount first, second;
  if (cut > 0) {
    std::exception_ptr error;
    std::thread other([&] {
      try {
        second = CountRange(fd, cut, size, path);
      } catch (...) {
        error = std::current_exception();
      }
    });
    try {
      first = CountRange(fd, 0, cut, path);
    } catch (...) {
      other.join();
      throw;
    }
    other.join();
    if (error) std::rethrow_exception(error);
  } else {
    second = CountRange(fd, 0, size, path);
  }
  const long lines = first.lines + second.lines + (second.state == LineState::kContent);
  return lines > 0 ? lines - 1 : 0;  // minus the header
}

long internal::CsvLineStartFrom(const std::string& path, long at) {
  const OpenFile file(path);
  return file.size >= 0 ? LineStartFrom(file.fd, at, file.size) : 0;
}

long internal::CountCsvLinesFrom(const std::string& path, long begin) {
  const OpenFile file(path);
  const RangeCount count = CountRange(file.fd, begin, file.size, path);
  return count.lines + (count.state == LineState::kContent);
}

}  // namespace ident::workflow
