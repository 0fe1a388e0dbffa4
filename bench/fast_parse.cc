// The reference for bench/read_speed.py: a plain fast parse of a comma-separated file of numbers, the floor
// of what reading a record costs. Reads the file in 1 MiB blocks (read(2)), skips the header line, converts
// every cell with std::from_chars and prints the number of rows and the sum of all values (so nothing is
// optimised away). No checks beyond what from_chars does: a cell it cannot convert ends the program.
//
//   build/bench/fast_parse FILE      # prints "rows <N> sum <S>"
#include <fcntl.h>
#include <unistd.h>

#include <charconv>
#include <cstdio>
#include <cstring>
#include <vector>

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: fast_parse FILE\n");
    return 2;
  }
  const int fd = open(argv[1], O_RDONLY);
  if (fd < 0) {
    std::perror(argv[1]);
    return 1;
  }
  constexpr std::size_t kBlock = 1 << 20;
  std::vector<char> buffer(2 * kBlock);
  std::size_t kept = 0;  // bytes of an unfinished line carried to the front of the buffer
  bool header = true;
  long rows = 0;
  double sum = 0;
  while (true) {
    const ssize_t got = read(fd, buffer.data() + kept, buffer.size() - kept);
    if (got < 0) {
      std::perror(argv[1]);
      return 1;
    }
    const char* p = buffer.data();
    const char* const end = buffer.data() + kept + got;
    const bool last = got == 0;
    while (p < end) {
      const char* eol = static_cast<const char*>(std::memchr(p, '\n', static_cast<std::size_t>(end - p)));
      if (eol == nullptr) {
        if (!last) break;
        eol = end;
      }
      if (header) {
        header = false;
      } else if (eol > p) {
        const char* q = p;
        while (q < eol) {
          double v = 0;
          const auto [ptr, ec] = std::from_chars(q, eol, v);
          if (ec != std::errc()) {
            std::fprintf(stderr, "%s: row %ld: not a number\n", argv[1], rows + 1);
            return 1;
          }
          sum += v;
          q = ptr + 1;  // past the comma (or the line end)
        }
        ++rows;
      }
      p = eol + 1;
    }
    if (last) break;
    kept = static_cast<std::size_t>(end - p);
    if (kept == buffer.size()) {
      std::fprintf(stderr, "%s: a line longer than %zu bytes\n", argv[1], buffer.size());
      return 1;
    }
    std::memmove(buffer.data(), p, kept);
  }
  close(fd);
  std::printf("rows %ld sum %.17g\n", rows, sum);
  return 0;
}
