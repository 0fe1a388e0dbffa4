#include "ident/io/csv.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <optional>
#include <string>
#include <string_view>
#include <tuple>
#include <vector>

#include "common/error.h"
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
  const auto path = WriteFile("ok.csv", "\xEF\xBB\xBFt, u ,y\r\n\r\n0,+1.5, 2e3\r\n1,-2,3\r\n\r\n \t\n\n");
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
  ExpectDataError(WriteFile("inf.csv", "t,u,y\n0,-inf,1\n"),
                  "inf.csv:2: column 2 ('u'): '-inf' is not a finite number");
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
TEST(CsvReader, EmptyColumnName) {
  ExpectDataError(WriteFile("en.csv", "t,,y\n0,1,2\n"), "en.csv:1: column 2 has an empty name");
}
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
  CsvReader reader(WriteFile("s.csv", "a,b\n\n1,2\n3,4\n\n"));
  Eigen::VectorXd row(2);
  ASSERT_TRUE(reader.Next(row));
  EXPECT_EQ(reader.line(), 3);
  ASSERT_TRUE(reader.Next(row));
  EXPECT_EQ(reader.line(), 4);
  EXPECT_EQ(row(1), 4);
  EXPECT_FALSE(reader.Next(row));
  EXPECT_EQ(reader.rows_read(), 2);
}

// Old Mac files end lines with CR alone: read as line ends, mixed with LF and CRLF, lines counted once.
TEST(CsvReader, ReadsCrOnlyLineEnds) {
  const DataTable t = ReadCsv(WriteFile("cr.csv", "t,u\r0,1.5\r1,-2\r\n2,7\n3,9\r"));
  EXPECT_EQ(t.names, (std::vector<std::string>{"t", "u"}));
  ASSERT_EQ(t.num_rows(), 4);
  EXPECT_EQ(t.values(0, 1), 1.5);
  EXPECT_EQ(t.values(1, 1), -2);
  EXPECT_EQ(t.values(2, 1), 7);
  EXPECT_EQ(t.values(3, 1), 9);
  ExpectDataError(WriteFile("cr_bad.csv", "t,u\r0,1\r\n1,x\r2,3\r"),
                  "cr_bad.csv:3: column 2 ('u'): 'x' is not a number");
}

// A CRLF split across the reader's 64 KiB blocks is one line end.
TEST(CsvReader, CrlfAcrossBlockBoundariesIsOneLineEnd) {
  std::string text = "t,u\r\n";
  int rows = 0;
  while (text.size() < 3 * 65536) text += fmt::format("{},{}\r\n", rows, rows % 7), ++rows;
  CsvReader reader(WriteFile("crlf_blocks.csv", text));
  Eigen::VectorXd row(2);
  long n = 0;
  while (reader.Next(row)) {
    ASSERT_EQ(row(0), static_cast<double>(n)) << "line " << reader.line();
    ASSERT_EQ(reader.line(), n + 2);
    ++n;
  }
  EXPECT_EQ(n, rows);
}

TEST(CsvReader, BlankLineBetweenDataRowsIsAGap) {
  ExpectDataError(WriteFile("gap.csv", "t,u\n0,1\n1,2\n\n2,3\n"),
                  "gap.csv:4: blank line inside the data (a gap in the record?)");
  ExpectDataError(WriteFile("gap2.csv", "t,u\r\n0,1\r\n \t\r\n\r\n2,3\r\n"), "gap2.csv:3: blank line inside the data");
  // Blank lines before the header, between it and the first row, and at the end stay allowed.
  EXPECT_EQ(ReadCsv(WriteFile("ends.csv", "\n\nt,u\n\n0,1\n1,2\n\n \n")).num_rows(), 2);
}

TEST(CsvReader, PlusFollowedByASignIsNotANumber) {
  ExpectDataError(WriteFile("pm.csv", "t,u\n0,+-5\n"), "pm.csv:2: column 2 ('u'): '+-5' is not a number");
  ExpectDataError(WriteFile("pp.csv", "t,u\n0,++5\n"), "pp.csv:2: column 2 ('u'): '++5' is not a number");
  EXPECT_EQ(ReadCsv(WriteFile("p.csv", "t,u\n0,+5\n")).values(0, 1), 5);
}

// The line limit bounds the memory of a line: a line of exactly kMaxCsvLineBytes bytes is read, one
// byte more is refused with the line's number (a 1 MiB run of zeros, as /dev/zero gives, included).
TEST(CsvReader, LinesAreLimitedTo1MiB) {
  ASSERT_EQ(kMaxCsvLineBytes, 1048576u);
  const std::string at_limit = "1," + std::string(kMaxCsvLineBytes - 3, '0') + "5";
  ASSERT_EQ(at_limit.size(), kMaxCsvLineBytes);
  const DataTable t = ReadCsv(WriteFile("at_limit.csv", "t,u\n" + at_limit + "\n"));
  EXPECT_EQ(t.values(0, 1), 5);
  ExpectDataError(WriteFile("over.csv", "t,u\n0,1\n" + at_limit + "0\n"), "over.csv:3: line longer than 1048576 bytes");
  ExpectDataError(WriteFile("zeros.csv", std::string(kMaxCsvLineBytes + 1, '\0')),
                  "zeros.csv:1: line longer than 1048576 bytes");
}

// A long cell is shown by its first 32 bytes and its length: the message stays short.
TEST(CsvReader, LongCellIsEchoedTruncatedWithItsLength) {
  const std::string cell(100000, 'x');
  try {
    ReadCsv(WriteFile("long_cell.csv", "t,u\n0," + cell + "\n"));
    FAIL() << "no error";
  } catch (const DataError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("long_cell.csv:2: column 2 ('u'): '" + std::string(32, 'x') +
                           "...' (100000 bytes) is not a number"),
              std::string::npos)
        << message;
    EXPECT_LT(message.size(), 200u) << message;
  }
  EXPECT_EQ(ShowCell(std::string(32, 'a')), "'" + std::string(32, 'a') + "'");
  EXPECT_EQ(ShowCell("1\x1b[2J"), "'1\\x1b[2J'");  // control bytes escaped
  // The cut falls before a multi-byte character, not inside it: 31 ASCII bytes, then "é" (2 bytes).
  EXPECT_EQ(ShowCell(std::string(31, 'a') + "\xC3\xA9zz"), "'" + std::string(31, 'a') + "...' (35 bytes)");
}

TEST(CsvReader, NulBytesAreReportedNotCutTheMessage) {
  const std::string cell_nul(
      "t,u,y\n0,1\0"
      "2,3\n",
      14);
  try {
    ReadCsv(WriteFile("nul.csv", cell_nul));
    FAIL() << "no error";
  } catch (const DataError& e) {
    const std::string message(e.what());
    EXPECT_EQ(message.substr(message.find("nul.csv")), "nul.csv:2: column 2 ('u'): contains a NUL byte");
  }
  ExpectDataError(WriteFile("nul_name.csv", std::string("t,u\0v,y\n0,1,2\n", 14)),
                  "nul_name.csv:1: column 2 name contains a NUL byte");
}

// Duplicate names are found through a hash map, so a wide header is read in linear time; the column
// limit is 100000: the widest header is read, one more column is refused.
TEST(CsvReader, WideHeadersUpToTheColumnLimit) {
  ASSERT_EQ(kMaxCsvColumns, 100000);
  std::string header, row;
  for (int j = 0; j < kMaxCsvColumns; ++j) {
    header += fmt::format("{}c{}", j ? "," : "", j);
    row += fmt::format("{}{}", j ? "," : "", j);
  }
  const DataTable t = ReadCsv(WriteFile("widest.csv", header + "\n" + row + "\n"));
  ASSERT_EQ(t.names.size(), 100000u);
  EXPECT_EQ(t.values(0, 99999), 99999);
  EXPECT_EQ(t.ColumnIndex("c77777"), 77777);
  std::string dup = header;
  dup.replace(dup.rfind(','), std::string::npos, ",c0");  // the last column repeats the first
  ExpectDataError(WriteFile("wide_dup.csv", dup + "\n" + row + "\n"),
                  "wide_dup.csv:1: duplicate column name 'c0' (columns 1 and 100000)");
  ExpectDataError(WriteFile("too_wide.csv", header + ",extra\n" + row + ",1\n"),
                  "too_wide.csv:1: the header has 100001 columns; at most 100000 are supported");
  // An unknown column lists the first 20 names and the number of columns.
  try {
    t.ColumnIndex("q");
    FAIL();
  } catch (const DataError& e) {
    EXPECT_NE(std::string(e.what()).find("no column 'q' (columns: c0, c1, c2,"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(", c19, ... (100000 columns)"), std::string::npos) << e.what();
    EXPECT_LT(std::string(e.what()).size(), 300u);
  }
}

// Delimiters: ';', tab and whitespace runs are detected from the header and the first data line.
TEST(CsvReader, DetectsSemicolonTabAndWhitespace) {
  for (const auto& [name, text, expected] : std::vector<std::tuple<std::string, std::string, Delimiter>>{
           {"semi.csv", "t;u;y\n0;1.5;-2\n1;2;3e1\n", Delimiter::kSemicolon},
           {"tab.tsv", "t\tu\ty\n0\t1.5\t-2\n1\t2\t3e1\n", Delimiter::kTab},
           {"spaces.dat", "  t   u  y\n  0  1.5   -2\n1 2\t3e1  \n", Delimiter::kWhitespace},
           {"comma.csv", "t, u, y\n0, 1.5, -2\n1, 2, 3e1\n", Delimiter::kComma}}) {
    CsvReader reader(WriteFile(name, text));
    EXPECT_EQ(reader.delimiter(), expected) << name;
    const DataTable t = ReadCsv(WriteFile(name, text));
    ASSERT_EQ(t.names, (std::vector<std::string>{"t", "u", "y"})) << name;
    ASSERT_EQ(t.num_rows(), 2) << name;
    EXPECT_EQ(t.values(0, 1), 1.5) << name;
    EXPECT_EQ(t.values(0, 2), -2) << name;
    EXPECT_EQ(t.values(1, 2), 30) << name;
    EXPECT_FALSE(t.generated_names);
  }
  // Names with spaces stay one column in a comma, ';' or tab file; a one-column file stays one column.
  EXPECT_EQ(ReadCsv(WriteFile("sp_names.csv", "time s;u in V\n0;1\n")).names,
            (std::vector<std::string>{"time s", "u in V"}));
  EXPECT_EQ(ReadCsv(WriteFile("sp_tab.csv", "time s\tu\n0\t1\n")).names, (std::vector<std::string>{"time s", "u"}));
  EXPECT_EQ(ReadCsv(WriteFile("one.csv", "my signal\n1.5\n2\n")).names, (std::vector<std::string>{"my signal"}));
}

TEST(CsvReader, GivenDelimiterIsUsed) {
  const DataTable t = ReadCsv(WriteFile("given.csv", "a b;c\n1;2\n"), {.delimiter = Delimiter::kSemicolon});
  EXPECT_EQ(t.names, (std::vector<std::string>{"a b", "c"}));
  EXPECT_EQ(t.values(0, 1), 2);
  const DataTable w = ReadCsv(WriteFile("given_ws.csv", "a b\n1 2\n"), {.delimiter = Delimiter::kWhitespace});
  EXPECT_EQ(w.values(0, 1), 2);
  EXPECT_EQ(ParseDelimiter("tab"), Delimiter::kTab);
  EXPECT_EQ(ParseDelimiter("space"), Delimiter::kWhitespace);
  EXPECT_EQ(ParseDelimiter(";"), Delimiter::kSemicolon);
  EXPECT_EQ(ParseDelimiter(","), Delimiter::kComma);
  EXPECT_EQ(ParseDelimiter("auto"), Delimiter::kAuto);
  EXPECT_THROW(ParseDelimiter("|"), InvalidArgument);
}

TEST(CsvReader, DelimiterErrorsAndHints) {
  ExpectDataError(WriteFile("amb.csv", "# two delimiters\na,b;c,d;e\n1,2;3,4;5\n"),
                  "amb.csv:2: cannot tell the delimiter: ',' and ';' both split the header and line 3");
  ExpectDataError(WriteFile("wrong.csv", "t;u;y\n0;1;2\n"),
                  "wrong.csv:1: the header has one column with the delimiter ','; the file looks ';'-separated "
                  "(pass --delimiter ';')",
                  {.delimiter = Delimiter::kComma});
  ExpectDataError(WriteFile("dec.csv", "t;u;y\n0;1.5;2\n1;1,5;2\n"),
                  "dec.csv:3: column 2 ('u'): '1,5' is not a number (the delimiter is ';': decimals take '.', not "
                  "',')");
  ExpectDataError(WriteFile("amb2.csv", "a,b;c\n1\n"),
                  "amb2.csv:1: cannot tell the delimiter: ',' and ';' both split the header into");
  ExpectDataError(WriteFile("ragged.dat", "1 2 3\n4 5\n"), "ragged.dat:2: row has 2 fields; the header has 3");
  ExpectDataError(WriteFile("long.dat", "1 2\n4 5 6 7\n"), "long.dat:2: row has 4 fields; the header has 2");
  ExpectDataError(WriteFile("long.tsv", "a\tb\n4\t5\t6\t7\n"), "long.tsv:2: row has 4 fields; the header has 2");
}

// A first line of numbers is data: DaISy .dat files have no header; the columns are c1, c2, ...
TEST(CsvReader, HeaderlessNumericFilesGetGeneratedNames) {
  const std::string path = WriteFile("daisy.dat", "   1.0000000e+00  -2.5e-01   3\n   4  5.5 -6\n\n");
  const DataTable t = ReadCsv(path);
  EXPECT_TRUE(t.generated_names);
  ASSERT_EQ(t.names, (std::vector<std::string>{"c1", "c2", "c3"}));
  ASSERT_EQ(t.num_rows(), 2);
  EXPECT_EQ(t.values(0, 0), 1);
  EXPECT_EQ(t.values(0, 1), -0.25);
  EXPECT_EQ(t.values(1, 2), -6);
  EXPECT_EQ(t.Line(0), 1);
  EXPECT_EQ(t.Line(1), 2);
  CsvReader reader(path);
  Eigen::VectorXd row(3);
  ASSERT_TRUE(reader.Next(row));
  EXPECT_EQ(reader.line(), 1);
  ASSERT_TRUE(reader.Next(row));
  EXPECT_EQ(reader.line(), 2);
  EXPECT_FALSE(reader.Next(row));
  // One line, comma-separated, with a missing cell; a single number.
  const DataTable m = ReadCsv(WriteFile("one_row.csv", "1,,3\n"), {.missing_as_nan = true});
  ASSERT_EQ(m.num_rows(), 1);
  EXPECT_TRUE(std::isnan(m.values(0, 1)));
  EXPECT_EQ(m.values(0, 2), 3);
  EXPECT_EQ(ReadCsv(WriteFile("single.dat", "7\n8\n")).values(1, 0), 8);
  // A bad cell of the first line is named by its line.
  ExpectDataError(WriteFile("first_bad.dat", "1 2 3\n1 2 x\n"),
                  "first_bad.dat:2: column 3 ('c3'): 'x' is not a number");
}

TEST(CsvReader, CommentLinesAreSkippedAndCounted) {
  const std::string path = WriteFile(
      "comments.csv", "# recorded 2 rows\n  # units: s, V, V\nt,u,y\n# first\n0,1,2\n\t# between\n1,3,4\n#end\n");
  const DataTable t = ReadCsv(path);
  ASSERT_EQ(t.names, (std::vector<std::string>{"t", "u", "y"}));
  ASSERT_EQ(t.num_rows(), 2);
  EXPECT_EQ(t.values(1, 1), 3);
  EXPECT_EQ(t.Line(0), 5);
  EXPECT_EQ(t.Line(1), 7);
  ExpectDataError(WriteFile("comments_bad.csv", "#c\nt,u\n#c\n0,1\n#c\n1,z\n"),
                  "comments_bad.csv:6: column 2 ('u'): 'z' is not a number");
  ExpectDataError(WriteFile("only_comments.csv", "# nothing\n#\n"), "only_comments.csv: the file is empty");
  ExpectDataError(WriteFile("comment_rows.csv", "t,u\n# nothing\n"), "comment_rows.csv: no data rows after the header");
}

// CsvOptions::on_read sees the bytes taken so far after each block: increasing, ending at the file's size,
// and the table read with it is the table read without.
TEST(CsvReader, OnReadReportsTheBytesTakenUpToTheFileSize) {
  std::string text = "t,y\n";
  for (int k = 0; k < 40'000; ++k) text += fmt::format("{},{}\n", k, 0.25 * k);
  const std::string path = WriteFile("on_read.csv", text);
  std::vector<long> seen;
  CsvOptions options;
  options.on_read = [&seen](long bytes) { seen.push_back(bytes); };
  const DataTable with = ReadCsv(path, options);
  ASSERT_GE(seen.size(), 2u);  // a file of several blocks
  for (std::size_t i = 1; i < seen.size(); ++i) EXPECT_GT(seen[i], seen[i - 1]);
  EXPECT_EQ(seen.back(), static_cast<long>(text.size()));
  const DataTable without = ReadCsv(path);
  EXPECT_EQ(with.values, without.values);
}

// CsvOptions::on_bytes sees the input's bytes in order, all of them: their concatenation is the file.
TEST(CsvReader, OnBytesSeesTheWholeFileInOrder) {
  std::string text = "# a comment\nt,y\n";
  for (int k = 0; k < 40'000; ++k) text += fmt::format("{},{}\n", k, 0.25 * k);
  text += "\n\n";
  const std::string path = WriteFile("on_bytes.csv", text);
  std::string seen;
  int blocks = 0;
  CsvOptions options;
  options.on_bytes = [&](std::string_view bytes) { seen += bytes, ++blocks; };
  const DataTable with = ReadCsv(path, options);
  EXPECT_GE(blocks, 2);  // a file of several blocks
  EXPECT_EQ(seen, text);
  EXPECT_EQ(with.values, ReadCsv(path).values);
}

// ReadCsvUpTo gives ReadCsv's table for a file of at most max_rows rows, and std::nullopt for a longer one,
// whose rest it leaves unread (here: most of a 1.3 MB file after row 11).
TEST(CsvReader, ReadCsvUpToStopsAfterTheRowPastTheLimit) {
  std::string text = "t,y\n";
  for (int k = 0; k < 100'000; ++k) text += fmt::format("{},{}\n", k, 0.25 * k);
  const std::string path = WriteFile("up_to.csv", text);
  const std::optional<DataTable> all = ReadCsvUpTo(path, 100'000);
  ASSERT_TRUE(all.has_value());
  EXPECT_EQ(all->values, ReadCsv(path).values);
  EXPECT_EQ(all->names, (std::vector<std::string>{"t", "y"}));
  EXPECT_FALSE(ReadCsvUpTo(path, 99'999).has_value());
  long taken = 0;
  CsvOptions options;
  options.on_read = [&taken](long bytes) { taken = bytes; };
  EXPECT_FALSE(ReadCsvUpTo(path, 10, options).has_value());
  EXPECT_LT(taken, static_cast<long>(text.size()) / 2) << "read on past the limit";
  // Without a header the first line is a row.
  const std::string headerless = WriteFile("up_to_headerless.csv", "1,2\n3,4\n");
  ASSERT_TRUE(ReadCsvUpTo(headerless, 2).has_value());
  EXPECT_EQ(ReadCsvUpTo(headerless, 2)->num_rows(), 2);
  EXPECT_FALSE(ReadCsvUpTo(headerless, 1).has_value());
}

}  // namespace
}  // namespace ident::io
