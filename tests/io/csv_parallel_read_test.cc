// The parallel path of the read-ahead reader (ident/io/csv_read_ahead.h, ident/io/internal/plain_segments.h)
// against CsvReader on files large enough to take it: the same rows, line numbers and errors, whatever line
// stops the plain rows and wherever it stands among the segments.
#include <random>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "common/error.h"
#include "ident/io/csv.h"
#include "ident/io/csv_read_ahead.h"
#include "ident/io/internal/plain_segments.h"
#include "tests/io/read_rows.h"
#include "tests/support/cli.h"

namespace ident::io {
namespace {

using ::ident::testing::WriteFile;

// The data lines of a record a little over CsvReadAhead::kSegmentedFileBytes: "k,u,y" with u and y random doubles
// of up to 17 significant digits (so that every digit of the conversion counts), some of them integers or
// in exponent notation.
std::vector<std::string> DataLines() {
  std::mt19937_64 rng(7);
  std::normal_distribution<double> normal;
  std::vector<std::string> lines;
  long bytes = 0;
  for (long k = 1; bytes < CsvReadAhead::kSegmentedFileBytes + CsvReadAhead::kSegmentBytes / 3; ++k) {
    const double u = normal(rng), y = normal(rng) * 1e3;
    lines.push_back(k % 97 == 0  ? fmt::format("{},{:.3e},{}", k, u, static_cast<int>(y))
                    : k % 2 == 0 ? fmt::format("{},{:.17g},{:.17g}", k, u, y)
                                 : fmt::format("{},{:.6g},{:.9g}", k, u, y));
    bytes += static_cast<long>(lines.back().size()) + 1;
  }
  return lines;
}

std::string Join(const std::string& first, const std::vector<std::string>& lines, std::size_t from = 0,
                 std::size_t to = std::string::npos) {
  std::string text = first;
  to = std::min(to, lines.size());
  for (std::size_t i = from; i < to; ++i) text += lines[i] + "\n";
  return text;
}

void ExpectSameAsCsvReader(const std::string& path, std::size_t expected_rows) {
  CsvReadAhead ahead(path);
  const ReadRows got = ReadEvery(ahead);
  CsvReader plain(path);
  const ReadRows want = ReadEvery(plain);
  EXPECT_EQ(got.error, want.error) << path;
  EXPECT_EQ(got.lines.size(), expected_rows) << path;
  EXPECT_EQ(got.lines, want.lines) << path;
  EXPECT_TRUE(got.values == want.values) << path;
  Eigen::VectorXd row(ahead.num_columns());
  if (want.error.empty()) {
    EXPECT_FALSE(ahead.Next(row)) << path;  // and stays at the end
  }
}

TEST(CsvParallelRead, GivesCsvReadersRowsAndLines) {
  const std::vector<std::string> lines = DataLines();
  ExpectSameAsCsvReader(WriteFile("parallel.csv", Join("k,u,y\n", lines)), lines.size());
  // No header: the first line is the first row. No line end after the last line.
  std::string text = Join("", lines);
  text.pop_back();
  ExpectSameAsCsvReader(WriteFile("parallel_no_header.csv", text), lines.size());
  // Semicolons.
  std::string semicolons = Join("k;u;y\n", lines);
  std::replace(semicolons.begin(), semicolons.end(), ',', ';');
  ExpectSameAsCsvReader(WriteFile("parallel_semicolons.csv", semicolons), lines.size());
}

TEST(CsvParallelRead, GoesOnFromTheFirstLineThatIsNotAPlainRow) {
  const std::vector<std::string> lines = DataLines();
  const std::size_t n = lines.size();
  // Each kind of line at one of three positions among the segments: in the first, in the middle, just
  // before the end.
  const std::size_t positions[] = {5, n / 2 + 3, n - 2};
  const struct {
    const char* name;
    const char* line;
    std::size_t rows;  // the rows before the end or the error: n or n + 1, or 0 for the position
  } cases[] = {{"comment", "# a comment\n", n},
               {"spaces", " 0.5 , 1e3,\t-2\n", n + 1},
               {"plus", "+1,+2.5,3\n", n + 1},
               {"crlf", "1,2,3\r\n", n + 1},
               {"bad", "1,x,3\n", 0},
               {"ragged", "1,2\n", 0},
               {"blank", "\n", 0},
               {"nan", "1,nan,3\n", 0}};
  for (std::size_t k = 0; k < std::size(cases); ++k) {
    const std::size_t at = positions[k % 3];
    const std::string path = WriteFile(fmt::format("parallel_{}.csv", cases[k].name),
                                       Join("k,u,y\n", lines, 0, at) + cases[k].line + Join("", lines, at));
    ExpectSameAsCsvReader(path, cases[k].rows == 0 ? at : cases[k].rows);
  }
  // With --missing a NaN cell is a row.
  const std::string path =
      WriteFile("parallel_missing.csv", Join("k,u,y\n", lines, 0, n / 2) + "1,,3\n" + Join("", lines, n / 2));
  CsvOptions missing;
  missing.missing_as_nan = true;
  CsvReadAhead ahead(path, missing);
  const ReadRows got = ReadEvery(ahead);
  EXPECT_EQ(got.error, "");
  ASSERT_EQ(got.lines.size(), n + 1);
  EXPECT_TRUE(std::isnan(got.values[3 * (n / 2) + 1]));
  EXPECT_EQ(got.lines[n / 2], static_cast<long>(n / 2) + 2);
  EXPECT_EQ(got.lines.back(), static_cast<long>(n) + 2);
}

TEST(CsvParallelRead, FirstLinesThatAreNotAPlainHeaderTakeCsvReader) {
  const std::vector<std::string> lines = DataLines();
  ExpectSameAsCsvReader(WriteFile("parallel_comment_first.csv", Join("# from a logger\nk,u,y\n", lines)), lines.size());
  ExpectSameAsCsvReader(WriteFile("parallel_crlf_header.csv", Join("k,u,y\r\n", lines)), lines.size());
  ExpectSameAsCsvReader(WriteFile("parallel_bom.csv", Join("\xEF\xBB\xBFk,u,y\n", lines)), lines.size());
}

// PlainSegments alone, with segments of a few kilobytes: many segment boundaries, lines that run over a
// segment and its first tail step, and a stop at the first line that is not a plain row.
TEST(CsvParallelRead, SegmentsEndAndStartAtLineBoundaries) {
  std::vector<std::string> lines;
  for (int k = 1; k <= 3000; ++k)
    lines.push_back(k % 500 == 0 ? fmt::format("{},{},{:0>9000}", k, k + 0.5, k)
                                 : fmt::format("{},{},{}", k, k + 0.5, k * 3));
  for (const long segment_bytes : {long{1} << 10, long{4093}, long{1} << 16}) {
    for (const bool header : {true, false}) {
      const std::string text = Join(header ? "k,u,y\n" : "", lines);
      const std::string path = WriteFile("segments.csv", text);
      internal::PlainSegments segments(path, header, static_cast<long>(text.size()), ',', 3, 2, segment_bytes);
      EXPECT_EQ(segments.first_line(), header ? 2 : 1);
      double row[3];
      int rows = 0;
      bool in_order = true;
      while (segments.Next(row)) {
        ++rows;
        in_order = in_order && row[0] == rows && row[1] == rows + 0.5 && row[2] == (rows % 500 == 0 ? rows : 3 * rows);
      }
      EXPECT_FALSE(segments.stopped()) << segment_bytes;
      EXPECT_EQ(rows, 3000) << segment_bytes;
      EXPECT_TRUE(in_order) << segment_bytes;
    }
  }
  const std::string text = Join("k,u,y\n", lines, 0, 1234) + "1, 2,3\n" + Join("", lines, 1234);
  const std::string path = WriteFile("segments_stop.csv", text);
  internal::PlainSegments segments(path, true, static_cast<long>(text.size()), ',', 3, 2, 1 << 10);
  double row[3];
  int rows = 0;
  while (segments.Next(row)) ++rows;
  EXPECT_TRUE(segments.stopped());
  EXPECT_EQ(rows, 1234);
}

TEST(CsvParallelRead, StopsWhenDroppedPartWay) {
  const std::string path = WriteFile("parallel_drop.csv", Join("k,u,y\n", DataLines()));
  for (int taken : {0, 1, 5000, 100'000}) {
    CsvReadAhead reader(path);
    Eigen::VectorXd row(3);
    for (int k = 0; k < taken; ++k) ASSERT_TRUE(reader.Next(row));
    if (taken > 0) {
      EXPECT_EQ(row(0), taken);
      EXPECT_EQ(reader.line(), taken + 1);
    }
  }  // each destructor returns: the test ends
}

}  // namespace
}  // namespace ident::io
