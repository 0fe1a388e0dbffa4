#include "ident/io/csv.h"

#include <gtest/gtest.h>

#include "ident/common/error.h"
#include "tests/support/cli.h"
#include "tests/support/test_data.h"

namespace ident::io {
namespace {

using ::ident::testing::WriteFile;

// Expects ReadCsv(path) to throw DataError whose message contains `needle`.
void ExpectDataError(const std::string& path, const std::string& needle, CsvOptions options = {}) {
  try {
    ReadCsv(path, options);
    ADD_FAILURE() << "no error for " << path;
  } catch (const DataError& e) {
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << "message: " << e.what();
    EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos) << "message is not one line";
  }
}

TEST(CsvReader, ReadsTheBundledDryerRecord) {
  const DataTable t = ReadCsv(ident::testing::DatasetPath("dryer.csv"));
  ASSERT_EQ(t.names, (std::vector<std::string>{"t", "u", "y"}));
  ASSERT_EQ(t.num_rows(), 1000);
  EXPECT_DOUBLE_EQ(t.values(0, 1), 6.41);
  EXPECT_DOUBLE_EQ(t.values(1, 2), 4.7636589);
  EXPECT_DOUBLE_EQ(t.values(999, 0), 79.92);
}

TEST(CsvReader, AcceptsCrlfBlankLinesBomSpacesAndPlusSigns) {
  const auto path = WriteFile("ok.csv", "\xEF\xBB\xBFt, u ,y\r\n0,+1.5, 2e3\r\n\r\n1,-2,3\r\n\n");
  const DataTable t = ReadCsv(path);
  EXPECT_EQ(t.names, (std::vector<std::string>{"t", "u", "y"}));
  ASSERT_EQ(t.num_rows(), 2);
  EXPECT_EQ(t.values(0, 1), 1.5);
  EXPECT_EQ(t.values(0, 2), 2000);
  EXPECT_EQ(t.values(1, 1), -2);
}

TEST(CsvReader, MissingFileNamesTheFile) { ExpectDataError("/nonexistent/x.csv", "cannot open '/nonexistent/x.csv'"); }
TEST(CsvReader, DirectoryIsRejected) { ExpectDataError(ident::testing::TempDir(), "is a directory"); }
TEST(CsvReader, EmptyFile) { ExpectDataError(WriteFile("empty.csv", ""), "empty.csv: the file is empty"); }
TEST(CsvReader, BlankFileCountsAsEmpty) { ExpectDataError(WriteFile("blank.csv", "\n \n"), "the file is empty"); }
TEST(CsvReader, HeaderOnly) { ExpectDataError(WriteFile("h.csv", "t,u,y\n"), "h.csv: no data rows after the header"); }
TEST(CsvReader, RaggedRowTooShort) {
  ExpectDataError(WriteFile("r1.csv", "t,u,y\n0,1,2\n1,2\n"), "r1.csv:3: row has 2 fields; the header has 3");
}
TEST(CsvReader, RaggedRowTooLong) {
  ExpectDataError(WriteFile("r2.csv", "t,u,y\n0,1,2,3\n"), "r2.csv:2: row has 4 fields; the header has 3");
}
TEST(CsvReader, NonNumericValueNamesLineAndColumn) {
  ExpectDataError(WriteFile("n.csv", "t,u,y\n0,1,2\n1,abc,2\n"), "n.csv:3: column 2 ('u'): 'abc' is not a number");
  ExpectDataError(WriteFile("n2.csv", "t,u,y\n0,1,2x\n"), "n2.csv:2: column 3 ('y'): '2x' is not a number");
}
TEST(CsvReader, NanAndInfAreRejectedByDefault) {
  ExpectDataError(WriteFile("nan.csv", "t,u,y\n0,1,nan\n"), "nan.csv:2: column 3 ('y'): 'nan' is not a finite number");
  ExpectDataError(WriteFile("inf.csv", "t,u,y\n0,-inf,1\n"), "inf.csv:2: column 2 ('u'): '-inf' is not a finite number");
  ExpectDataError(WriteFile("e.csv", "t,u,y\n0,,1\n"), "e.csv:2: column 2 ('u') is empty");
}
TEST(CsvReader, NanInfAndEmptyBecomeMissingWhenAsked) {
  const DataTable t = ReadCsv(WriteFile("m.csv", "t,u,y\n0,nan,1\n1,,inf\n2,3,4\n"), {.missing_as_nan = true});
  ASSERT_EQ(t.num_rows(), 3);
  EXPECT_TRUE(std::isnan(t.values(0, 1)));
  EXPECT_TRUE(std::isnan(t.values(1, 1)));
  EXPECT_TRUE(std::isnan(t.values(1, 2)));
  EXPECT_EQ(t.values(2, 2), 4);
}
TEST(CsvReader, OutOfRangeValue) {
  ExpectDataError(WriteFile("big.csv", "t,u\n0,1e400\n"), "big.csv:2: column 2 ('u'): '1e400' is out of the range");
}
TEST(CsvReader, DuplicateColumnNames) {
  ExpectDataError(WriteFile("d.csv", "t,u,u\n0,1,2\n"), "d.csv:1: duplicate column name 'u' (columns 2 and 3)");
}
TEST(CsvReader, EmptyColumnName) { ExpectDataError(WriteFile("en.csv", "t,,y\n0,1,2\n"), "en.csv:1: column 2 has an empty name"); }
TEST(CsvReader, UnknownColumnListsTheColumns) {
  const DataTable t = ReadCsv(WriteFile("c.csv", "t,u,y\n0,1,2\n"));
  try {
    t.ColumnIndex("q");
    FAIL();
  } catch (const DataError& e) {
    EXPECT_NE(std::string(e.what()).find("no column 'q' (columns: t, u, y)"), std::string::npos) << e.what();
  }
}
TEST(CsvReader, StreamsRowByRowWithLineNumbers) {
  CsvReader reader(WriteFile("s.csv", "a,b\n1,2\n\n3,4\n"));
  Eigen::VectorXd row(2);
  ASSERT_TRUE(reader.Next(row));
  EXPECT_EQ(reader.line(), 2);
  ASSERT_TRUE(reader.Next(row));
  EXPECT_EQ(reader.line(), 4);
  EXPECT_EQ(row(1), 4);
  EXPECT_FALSE(reader.Next(row));
  EXPECT_EQ(reader.rows_read(), 2);
}

}  // namespace
}  // namespace ident::io
