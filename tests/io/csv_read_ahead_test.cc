// The read-ahead reader (ident/io/csv_read_ahead.h) against CsvReader on the same files: the same rows and
// line numbers in order, the same error after the same rows, and a reader dropped part-way stops.
#include "ident/io/csv_read_ahead.h"

#include <string>
#include <vector>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "common/error.h"
#include "ident/io/csv.h"
#include "tests/io/read_rows.h"
#include "tests/support/cli.h"

namespace ident::io {
namespace {

using ::ident::testing::WriteFile;

// `rows` rows of 3 columns, with a comment line every 1000 rows and the value of row k, column c
// k + c / 4 (exact in binary); `bad_row` (1-based, 0: none) has 'x' in its last column.
std::string Record(int rows, int bad_row = 0) {
  std::string text = "t,u,y\n";
  for (int k = 1; k <= rows; ++k) {
    if (k % 1000 == 0) text += "# a comment\n";
    if (k == bad_row)
      text += fmt::format("{},{},x\n", k, k + 0.25);
    else
      text += fmt::format("{},{},{}\n", k, k + 0.25, k + 0.5);
  }
  return text;
}

TEST(CsvReadAhead, GivesCsvReadersRowsAndLinesOverManyBlocks) {
  const int rows = 5 * CsvReadAhead::kBlocks * CsvReadAhead::kBlockRows + 17;
  const std::string path = WriteFile("read_ahead.csv", Record(rows));
  CsvReadAhead ahead(path);
  EXPECT_EQ(ahead.names(), (std::vector<std::string>{"t", "u", "y"}));
  const ReadRows got = ReadEvery(ahead);
  CsvReader plain(path);
  const ReadRows want = ReadEvery(plain);
  EXPECT_EQ(got.error, "");
  ASSERT_EQ(got.lines.size(), static_cast<std::size_t>(rows));
  EXPECT_EQ(got.values, want.values);
  EXPECT_EQ(got.lines, want.lines);
  // Row 1000 follows the first comment: line 1 is the header, line 1001 the comment.
  EXPECT_EQ(got.lines[999], 1002);
  EXPECT_EQ(got.values[3 * 999 + 2], 1000.5);
  Eigen::VectorXd row(3);
  EXPECT_FALSE(ahead.Next(row));  // and stays at the end
}

TEST(CsvReadAhead, ThrowsCsvReadersErrorAfterTheRowsBeforeIt) {
  const int bad = 3 * CsvReadAhead::kBlockRows + 5;
  const std::string path = WriteFile("read_ahead_bad.csv", Record(4 * CsvReadAhead::kBlockRows, bad));
  CsvReadAhead ahead(path);
  const ReadRows got = ReadEvery(ahead);
  CsvReader plain(path);
  const ReadRows want = ReadEvery(plain);
  EXPECT_EQ(got.lines.size(), static_cast<std::size_t>(bad - 1));
  EXPECT_EQ(got.values, want.values);
  EXPECT_NE(want.error.find("'x' is not a number"), std::string::npos) << want.error;
  EXPECT_EQ(got.error, want.error);
}

TEST(CsvReadAhead, HeaderErrorsAreThrownByTheConstructor) {
  const std::string path = WriteFile("read_ahead_header.csv", "u,u\n1,2\n");
  EXPECT_THROW(CsvReadAhead reader(path), DataError);
  EXPECT_THROW(CsvReadAhead reader("no/such/file.csv"), DataError);
  const std::string empty = WriteFile("read_ahead_empty.csv", "u,y\n");
  CsvReadAhead reader(empty);
  Eigen::VectorXd row(2);
  EXPECT_THROW(reader.Next(row), DataError);  // "no data rows after the header", from the reading thread
}

TEST(CsvReadAhead, StopsWhenDroppedPartWay) {
  const std::string path = WriteFile("read_ahead_drop.csv", Record(20 * CsvReadAhead::kBlockRows));
  for (int taken : {0, 1, CsvReadAhead::kBlockRows, 3 * CsvReadAhead::kBlockRows + 1}) {
    CsvReadAhead reader(path);
    Eigen::VectorXd row(3);
    for (int k = 0; k < taken; ++k) ASSERT_TRUE(reader.Next(row));
    if (taken > 0) {
      EXPECT_EQ(row(0), taken);
    }
  }  // each destructor returns: the test ends
}

TEST(CsvReadAhead, WideFilesGetShorterBlocks) {
  // 40 000 columns: one block holds one row (65 536 values at most), so 5 rows cross 5 blocks.
  const int columns = 40'000;
  std::string header, line;
  for (int c = 0; c < columns; ++c) {
    header += fmt::format("{}c{}", c ? "," : "", c);
    line += fmt::format("{}{}", c ? "," : "", c % 7);
  }
  std::string text = header + "\n";
  for (int k = 0; k < 5; ++k) text += line + "\n";
  CsvReadAhead reader(WriteFile("read_ahead_wide.csv", text));
  Eigen::VectorXd row(columns);
  int rows = 0;
  while (reader.Next(row)) {
    ++rows;
    EXPECT_EQ(row(columns - 1), (columns - 1) % 7);
  }
  EXPECT_EQ(rows, 5);
  EXPECT_EQ(reader.line(), 6);
}

}  // namespace
}  // namespace ident::io
