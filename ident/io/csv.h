// Reading recorded data from CSV files.
//
// Format: one header line of column names, comma-separated numeric rows, '.' decimal point,
// LF, CRLF or CR line ends; blank lines before the first data row and at the end of the file are
// ignored; a UTF-8 byte-order mark is skipped. Limits: a line holds at most kMaxCsvLineBytes bytes
// (1 MiB) and the header at most kMaxCsvColumns names. Every problem is reported as
// ident::DataError with one line naming the file, the line and the column:
//   cannot open 'x.csv': No such file or directory
//   x.csv: the file is empty
//   x.csv: no data rows after the header
//   x.csv:1: duplicate column name 'u' (columns 2 and 3)
//   x.csv:1: the header has 100001 columns; at most 100000 are supported
//   x.csv:7: line longer than 1048576 bytes
//   x.csv:7: row has 2 fields; the header has 3
//   x.csv:7: column 3 ('y'): 'abc' is not a number
//   x.csv:7: column 3 ('y'): 'nan' is not a finite number (pass --missing to treat NaN/Inf/empty cells as
//            missing samples)
//   x.csv:7: column 2 ('u'): contains a NUL byte
//   x.csv:7: blank line inside the data (a gap in the record?)
//   x.csv: no column 'q' (columns: t, u, y)
// A cell or name echoed in a message shows at most its first 32 bytes, control bytes as \xNN, and
// the length of a longer one: '00000000000000000000000000000000...' (1000000 bytes).
// With CsvOptions::missing_as_nan, empty cells and NaN/Inf values are stored as NaN (missing samples).
//
// Example:
//   ident::io::CsvReader reader("datasets/dryer.csv");        // streams rows, constant memory
//   Eigen::VectorXd row(reader.num_columns());
//   while (reader.Next(row)) { ... }
//   ident::io::DataTable table = ident::io::ReadCsv("datasets/dryer.csv");   // whole file
//   ident::io::DataTable t = ident::io::ParseCsv("u,y\n1,2\n", "<text>");   // text in memory
#pragma once

#include <cstddef>
#include <istream>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

namespace ident::io {

// A cell or name as messages show it: quoted, its first 32 bytes with control bytes as \xNN, and
// "... (N bytes)" for a longer one.
std::string ShowCell(std::string_view cell);

// The longest line the reader accepts, in bytes (without the line end).
inline constexpr std::size_t kMaxCsvLineBytes = 1 << 20;
// The most columns a header may name.
inline constexpr int kMaxCsvColumns = 100'000;

// The path that names standard input ("-", as most command-line tools take it).
inline constexpr const char* kStandardInput = "-";

// True for a regular file, which can be read more than once; false for standard input, a pipe, a FIFO or
// a device, which must be read once (into memory).
bool CanReadTwice(const std::string& path);

struct CsvOptions {
  bool missing_as_nan = false;  // store empty/NaN/Inf cells as NaN instead of rejecting them
};

// Streams a CSV file row by row (constant memory).
class CsvReader {
 public:
  // Opens the file (kStandardInput: reads standard input) and reads the header. Throws DataError.
  explicit CsvReader(const std::string& path, const CsvOptions& options = {});
  // Reads from `in`; `source` names it in messages (as the path does for files). Throws DataError.
  CsvReader(std::unique_ptr<std::istream> in, const std::string& source, const CsvOptions& options = {});

  const std::string& path() const { return path_; }
  const std::vector<std::string>& names() const { return names_; }
  int num_columns() const { return static_cast<int>(names_.size()); }
  // Index of a column by name; throws DataError listing the columns if there is none.
  int ColumnIndex(std::string_view name) const;
  // Reads the next data row into `row` (size num_columns()). Returns false at the end of the file
  // (and throws DataError "no data rows after the header" if there were none). Throws DataError.
  bool Next(Eigen::Ref<Eigen::VectorXd> row);
  // 1-based line number of the row last returned by Next().
  long line() const { return line_; }
  long rows_read() const { return rows_; }

 private:
  std::string path_;
  CsvOptions options_;
  void ReadHeader();
  // Reads the next line (LF, CRLF or CR ended) into buffer_ and counts it; false at the end of the input.
  bool ReadLine();
  // Refills chunk_ from the stream; false at its end.
  bool Fill();

  std::unique_ptr<std::istream> in_;
  std::vector<std::string> names_;
  std::string buffer_;
  std::vector<char> chunk_;
  std::size_t chunk_pos_ = 0, chunk_end_ = 0;
  bool skip_lf_ = false;  // the last line ended in CR: a following LF belongs to it
  long line_ = 0;
  long rows_ = 0;
  long blank_line_ = 0;  // first blank line after a data row (an error if another row follows)
};

// A whole record in memory: values(row, column).
struct DataTable {
  std::string source;  // file name, for messages
  std::vector<std::string> names;
  Eigen::MatrixXd values;
  // 0-based rows at which a further experiment starts (ascending, each in (0, rows)): the walkers of
  // ident/workflow restart the regressor history there, so no regressor straddles two experiments.
  std::vector<int> experiment_starts;

  int num_rows() const { return static_cast<int>(values.rows()); }
  bool StartsExperiment(int row) const;
  // Throws DataError "<source>: no column 'q' (columns: t, u, y)".
  int ColumnIndex(std::string_view name) const;
  Eigen::VectorXd Column(std::string_view name) const { return values.col(ColumnIndex(name)); }
};

// Reads the whole file. Throws DataError.
DataTable ReadCsv(const std::string& path, const CsvOptions& options = {});
// Parses CSV text held in memory; `source` names it in messages. Throws DataError.
DataTable ParseCsv(std::string_view text, const std::string& source, const CsvOptions& options = {});

// "<source>: no column 'q' (columns: t, u, y)" (shared by CsvReader and DataTable); at most 20
// names are listed, then the number of columns.
[[noreturn]] void ThrowUnknownColumn(const std::string& source, std::string_view name,
                                     const std::vector<std::string>& names);

}  // namespace ident::io
