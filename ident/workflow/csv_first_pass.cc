// ScanCsvFirstPass of ident/workflow/fit.h: a streamed fit's row count and detrending offsets in one read of
// the file.
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <istream>
#include <memory>
#include <optional>
#include <streambuf>
#include <string>
#include <string_view>
#include <system_error>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "common/error.h"
#include "ident/io/csv.h"
#include "ident/workflow/fit.h"
#include "ident/workflow/fit_record.h"
#include "ident/workflow/internal/csv_passes.h"
#include "ident/workflow/internal/first_pass.h"
#include "ident/workflow/internal/row_count.h"

namespace ident::workflow {
namespace {

// A file's first line (its header, line end included) and then its bytes from `offset` on: what a CsvReader
// reads as the rows from `offset` on under the file's header.
class HeaderThenFile : public std::istream {
 public:
  HeaderThenFile(const std::string& path, std::string header, long offset)
      : std::istream(nullptr), buffer_(path, std::move(header), offset) {
    rdbuf(&buffer_);
  }

 private:
  class Buffer : public std::streambuf {
   public:
    Buffer(const std::string& path, std::string header, long offset)
        : header_(std::move(header)), file_(path, std::ios::binary), block_(1 << 16) {
      io::internal::CountCsvFileOpened();
      file_.seekg(offset);
      setg(header_.data(), header_.data(), header_.data() + header_.size());
    }

   protected:
    int_type underflow() override {
      if (gptr() < egptr()) return traits_type::to_int_type(*gptr());
      if (!file_.read(block_.data(), std::ssize(block_)) && file_.gcount() <= 0) return traits_type::eof();
      setg(block_.data(), block_.data(), block_.data() + file_.gcount());
      return traits_type::to_int_type(*gptr());
    }

   private:
    std::string header_;
    std::ifstream file_;
    std::vector<char> block_;
  } buffer_;
};

// Where the estimation part of a file probably ends, from the bytes per line of 16 samples of 16 KiB spread
// evenly over the file (the first at its start), each taken for its sixteenth of the file; and the file's first
// line (its header, line end included). No value where a sample holds fewer than two line ends or the start
// holds a comment.
struct Guess {
  double end = 0;             // the byte where the estimation part's last row probably ends
  double bytes_per_line = 0;  // in the sixteenth where it ends
  double rows = 0;            // in the file, probably
  std::string header;
};
std::optional<Guess> GuessEstimationEnd(const std::string& path, long size, double split) {
  constexpr int kSamples = 16;
  constexpr long kSampleBytes = 1 << 14;
  std::ifstream in(path, std::ios::binary);
  io::internal::CountCsvFileOpened();
  const double part = static_cast<double>(size) / kSamples;
  std::vector<double> per_line(kSamples);
  std::string sample(static_cast<std::size_t>(kSampleBytes), '\0');
  Guess guess;
  for (int i = 0; i < kSamples; ++i) {
    in.clear();
    in.seekg(static_cast<std::streamoff>(part * i));
    in.read(sample.data(), kSampleBytes);
    const std::string_view got(sample.data(), static_cast<std::size_t>(std::max<std::streamsize>(in.gcount(), 0)));
    const long lines = std::count(got.begin(), got.end(), '\n');
    if (lines < 2) return std::nullopt;
    if (i == 0) {
      if (got.find('#') != std::string_view::npos) return std::nullopt;
      guess.header = std::string(got.substr(0, got.find('\n') + 1));
    }
    per_line[static_cast<std::size_t>(i)] = static_cast<double>(got.size()) / static_cast<double>(lines);
    guess.rows += part / per_line[static_cast<std::size_t>(i)];
  }
  const double target = split * guess.rows;
  double before = 0;  // rows in the sixteenths before the i-th
  for (int i = 0; i < kSamples; ++i) {
    const double b = per_line[static_cast<std::size_t>(i)], here = part / b;
    if (before + here >= target || i == kSamples - 1) {
      guess.end = part * i + (target - before) * b;
      guess.bytes_per_line = b;
      break;
    }
    before += here;
  }
  return guess;
}

}  // namespace

std::optional<CsvFirstPass> ScanCsvFirstPass(const std::string& path, const io::CsvOptions& csv, DataSource& source,
                                             const FitOptions& options, bool mean_squares) {
  return internal::ScanCsvFirstPass(path, csv, source, options, mean_squares, {});
}

std::optional<CsvFirstPass> internal::ScanCsvFirstPass(const std::string& path, const io::CsvOptions& csv,
                                                       DataSource& source, const FitOptions& options, bool mean_squares,
                                                       const FirstPassLimits& limits) {
  const double split = options.split;
  if (options.detrend != Detrend::kMean || !(split > 0 && split <= 1) || !io::CanReadTwice(path)) return std::nullopt;
  std::error_code ec;
  const auto file_size = std::filesystem::file_size(path, ec);
  if (ec) return std::nullopt;
  const long size = static_cast<long>(file_size);
  const std::optional<Guess> guess = GuessEstimationEnd(path, size, split);
  if (!guess) return std::nullopt;
  const std::string& header = guess->header;
  // The head [0, x) is parsed, the tail [x, size) counted. x: a line start a margin before where the
  // estimation part probably ends.
  long x = size;
  if (split < 1) {
    const double fraction = limits.margin_fraction * guess->rows;
    const double margin = fraction < 0 ? fraction : std::max(static_cast<double>(limits.min_margin_rows), fraction);
    const double at = guess->end - margin * guess->bytes_per_line;
    if (!(at > static_cast<double>(std::ssize(header)))) return std::nullopt;
    x = CsvLineStartFrom(path, static_cast<long>(at));
    if (x <= 0) return std::nullopt;
  }
  return DataErrorsFirst(path, csv, [&]() -> std::optional<CsvFirstPass> {
    const long tail = x < size ? CountCsvLinesFrom(path, x) : 0;
    io::CsvOptions head_csv = csv;
    head_csv.prefix_bytes = x;
    RecordRows reader(path, head_csv, nullptr, 2);
    const int columns = reader.num_columns();
    std::optional<ShiftedMeanSquares> squares;
    if (mean_squares) squares.emplace(source, columns);
    DetrendSums sums(source, options, columns, squares ? &*squares : nullptr);
    // Row r is in the estimation part whatever the head holds after it once r < ⌊split·(tail + r + 1)⌋; the
    // rows from the first that is not on are held until the count is complete.
    std::vector<double> held;
    bool overflow = false;
    Eigen::VectorXd row(columns);
    long r = 0, held_from = -1;
    for (; reader.Next(row); ++r) {
      if (held_from < 0 && r < EstimationRows(tail + r + 1, split)) {
        sums.Add(row);
        continue;
      }
      if (held_from < 0) held_from = r;
      overflow = overflow || std::ssize(held) + columns > limits.held_values;
      if (!overflow) held.insert(held.end(), row.data(), row.data() + columns);
    }
    CsvFirstPass first;
    first.layout = LayOutRows(path, source, options, r + tail, columns);
    first.data_lines = r + tail - (reader.generated_names() ? 1 : 0);
    const long estimation = first.layout.estimation.count;
    first.means_pass = overflow;
    for (long k = std::max(held_from, 0L); !overflow && held_from >= 0 && k < std::min(estimation, r); ++k)
      sums.Add(Eigen::Map<const Eigen::VectorXd>(held.data() + (k - held_from) * columns, columns));
    if (!first.means_pass && estimation > r) {  // the estimation part goes on in the tail: its rows up to there
      try {
        io::CsvReader rest(std::make_unique<HeaderThenFile>(path, header, x), path, csv);
        if (reader.generated_names()) rest.Next(row);  // the file's first line: a row of its own
        for (long k = r; k < estimation && !first.means_pass; ++k) {
          first.means_pass = !rest.Next(row);
          if (!first.means_pass) sums.Add(row);
        }
      } catch (const DataError&) {
        first.means_pass = true;  // reported by the means pass, at its line
      }
    }
    if (first.means_pass) {
      if (mean_squares) squares.emplace(source, columns);
      first.offset = DetrendOffsets(path, csv, source, options, first.layout, nullptr, squares ? &*squares : nullptr);
    } else {
      first.offset = sums.Offsets(path, reader.names(), columns);
    }
    if (squares) first.mean_squares = squares->Get(first.offset);
    return first;
  });
}

}  // namespace ident::workflow
