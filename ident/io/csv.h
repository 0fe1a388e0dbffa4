// Reading recorded data from CSV files.
//
// Format: a header line of column names, then numeric rows with '.' decimal points; LF, CRLF or CR line
// ends. The delimiter is ',', ';', a tab or runs of spaces/tabs (whitespace: DaISy .dat files), given as
// CsvOptions::delimiter or detected (Delimiter::kAuto): the one of ',', ';' and tab that splits the
// header; if several do, the one that splits the first data line into as many fields (two that fit, or
// none, are ambiguous); if none does, whitespace when it splits the header and the first data line into
// several fields, else ',' (one column). The first data line is read ahead only when the header does not
// decide.
// A first line whose cells are all numbers is data: the file has no header and its columns are named
// c1, c2, ... (CsvReader::generated_names()). Blank lines before the first data row and at the end and
// lines whose first non-blank byte is '#' (comments, anywhere) are skipped and counted in line numbers;
// a UTF-8 byte-order mark is skipped. Limits: a line holds at most kMaxCsvLineBytes bytes (1 MiB) and
// the header at most kMaxCsvColumns names. Every problem is reported as ident::DataError with one line
// naming the file, the line and the column:
//   cannot open 'x.csv': No such file or directory
//   x.csv: the file is empty
//   x.csv: no data rows after the header
//   x.csv:1: duplicate column name 'u' (columns 2 and 3)
//   x.csv:1: the header has 100001 columns; at most 100000 are supported
//   x.csv:1: cannot tell the delimiter: ',' and ';' both split the header and line 2 into several fields
//            (pass --delimiter)
//   x.csv:1: the header has one column with the delimiter ','; the file looks ';'-separated (pass
//            --delimiter ';')
//   x.csv:7: line longer than 1048576 bytes
//   x.csv:7: row has 2 fields; the header has 3
//   x.csv:7: column 3 ('y'): 'abc' is not a number
//   x.csv:7: column 3 ('y'): '1,5' is not a number (the delimiter is ';': decimals take '.', not ',')
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
#include <functional>
#include <istream>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
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

// How cells are separated: detected (kAuto), ',', ';', a tab, or runs of spaces and tabs.
enum class Delimiter { kAuto, kComma, kSemicolon, kTab, kWhitespace };

// The command-line spelling: "auto", ",", ";", "tab" or "space". Throws InvalidArgument otherwise.
Delimiter ParseDelimiter(std::string_view text);
// As messages and --delimiter name it: "','", "';'", "tab", "space" (kAuto: "auto").
std::string DelimiterName(Delimiter delimiter);

struct CsvOptions {
  bool missing_as_nan = false;  // store empty/NaN/Inf cells as NaN instead of rejecting them
  Delimiter delimiter = Delimiter::kAuto;
  // Called after each block the reader takes from its input, with the bytes taken so far (a long read's
  // progress); empty: not called.
  std::function<void(long)> on_read = nullptr;
  // Called with each block of bytes the reader takes from its input, in order (e.g. for a checksum of exactly
  // the bytes read); empty: not called.
  std::function<void(std::string_view)> on_bytes = nullptr;
  // ≥ 0: read only the input's first prefix_bytes bytes, as if the input ended there (a regular file read in
  // parts: the prefix should end where a line ends); negative: read to the end.
  long prefix_bytes = -1;
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
  // The delimiter in use (the detected one for Delimiter::kAuto).
  Delimiter delimiter() const { return delimiter_; }
  // True when the first line was data and the columns are named c1, c2, ...
  bool generated_names() const { return generated_names_; }

 private:
  std::string path_;
  CsvOptions options_;
  long bytes_taken_ = 0;  // from the input, for CsvOptions::on_read
  void ReadHeader();
  // Chooses delimiter_ from the header line and the first data line (`data`, null if none).
  void ChooseDelimiter(std::string_view header, const std::string_view* data);
  // Parses one data line into `row`; throws DataError naming line_.
  void ParseRow(std::string_view text, Eigen::Ref<Eigen::VectorXd> row);
  // The common row: num_columns() finite numbers, each ended by the separator, no spaces and no '+'. False
  // (`row` partly written) for any other line.
  bool ParsePlainRow(std::string_view text, Eigen::Ref<Eigen::VectorXd> row) const;
  double ParseCell(std::string_view cell, int column) const;
  // A cell the fast path of ParseCell does not take: '+'-signed, empty, NaN/Inf or bad (throws DataError).
  double ParseUncommonCell(std::string_view cell, int column) const;
  // Reads the next line (LF, CRLF or CR ended) into text_ and counts it; false at the end of the input.
  bool ReadLine();
  // The offset in chunk_ of the first LF or CR at or after chunk_pos_, chunk_end_ if none.
  std::size_t LineEnd();
  // Refills chunk_ from the stream; false at its end.
  bool Fill();

  std::unique_ptr<std::istream> in_;
  std::vector<std::string> names_;
  // The line ReadLine() read: a view into chunk_, or into buffer_ for a line that spans two chunks.
  std::string_view text_;
  std::string buffer_;
  std::vector<char> chunk_;
  std::size_t chunk_pos_ = 0, chunk_end_ = 0;
  std::size_t next_cr_ = 0;  // offset in chunk_ of the next CR at or after chunk_pos_ (chunk_end_: none)
  bool skip_lf_ = false;     // the last line ended in CR: a following LF belongs to it
  long line_ = 0;
  long rows_ = 0;
  long blank_line_ = 0;  // first blank line after a data row (an error if another row follows)
  Delimiter delimiter_ = Delimiter::kComma;
  char separator_ = ',';  // of delimiter_; 0 for whitespace runs
  bool generated_names_ = false;
  // Lines read ahead while the header was read and not yet returned by Next(): the first line of a file
  // without a header (header_, at header_line_) and the first data line (held_row_, at held_line_).
  bool header_is_row_ = false, held_ = false;
  std::string header_, held_row_;
  long header_line_ = 0, held_line_ = 0;
};

// A whole record in memory: values(row, column).
struct DataTable {
  std::string source;  // file name, for messages
  std::vector<std::string> names;
  Eigen::MatrixXd values;
  bool generated_names = false;  // the file had no header: columns c1, c2, ...
  // Where rows sit in the file: (row, line) wherever a row is not on the line after the previous row's
  // (the first row, and rows after comments or blank lines). Empty for a table not read from text.
  std::vector<std::pair<int, long>> row_lines;
  // 0-based rows at which a further experiment starts (ascending, each in (0, rows)): the walkers of
  // ident/workflow restart the regressor history there, so no regressor straddles two experiments.
  std::vector<int> experiment_starts;

  int num_rows() const { return static_cast<int>(values.rows()); }
  // The 1-based line of a 0-based row in its file; 0 when unknown.
  long Line(int row) const;
  bool StartsExperiment(int row) const;
  // Throws DataError "<source>: no column 'q' (columns: t, u, y)".
  int ColumnIndex(std::string_view name) const;
  Eigen::VectorXd Column(std::string_view name) const { return values.col(ColumnIndex(name)); }
};

// Reads the whole file. Throws DataError.
DataTable ReadCsv(const std::string& path, const CsvOptions& options = {});
// ReadCsv for a file of at most `max_rows` rows (DataTable::num_rows()); for a longer one, std::nullopt once row
// max_rows + 1 is read (the rest of the file is not read). Throws DataError as ReadCsv for the rows it reads.
std::optional<DataTable> ReadCsvUpTo(const std::string& path, long max_rows, const CsvOptions& options = {});
// Parses CSV text held in memory; `source` names it in messages. Throws DataError.
DataTable ParseCsv(std::string_view text, const std::string& source, const CsvOptions& options = {});

// The files opened for reading by CsvReader and by the row counts of ident/workflow in this process (a test's
// measure of how often a workflow reads a file).
long CsvFilesOpened();
namespace internal {
void CountCsvFileOpened();  // called by each such opening
}  // namespace internal

// "<source>: no column 'q' (columns: t, u, y)" (shared by CsvReader and DataTable); at most 20
// names are listed, then the number of columns.
[[noreturn]] void ThrowUnknownColumn(const std::string& source, std::string_view name,
                                     const std::vector<std::string>& names);

}  // namespace ident::io
