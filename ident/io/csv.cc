#include "ident/io/csv.h"

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <sstream>
#include <unordered_map>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "common/error.h"

namespace ident::io {
namespace {

std::string_view Trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) s.remove_suffix(1);
  return s;
}

bool IsSpace(char c) { return c == ' ' || c == '\t'; }

// Splits on `separator` (0: runs of spaces and tabs) into `fields` (views into `line`).
void Split(std::string_view line, char separator, std::vector<std::string_view>& fields) {
  fields.clear();
  if (separator == 0) {
    std::size_t pos = 0;
    while (true) {
      while (pos < line.size() && (IsSpace(line[pos]) || line[pos] == '\r')) ++pos;
      if (pos == line.size()) break;
      std::size_t end = pos;
      while (end < line.size() && !IsSpace(line[end]) && line[end] != '\r') ++end;
      fields.push_back(line.substr(pos, end - pos));
      pos = end;
    }
    return;
  }
  std::size_t start = 0;
  while (true) {
    const std::size_t at = line.find(separator, start);
    fields.push_back(Trim(line.substr(start, at == std::string_view::npos ? at : at - start)));
    if (at == std::string_view::npos) break;
    start = at + 1;
  }
}

// The number of fields `line` splits into at `separator` (0: runs of spaces and tabs).
std::size_t CountFields(std::string_view line, char separator) {
  if (separator != 0) return static_cast<std::size_t>(std::count(line.begin(), line.end(), separator)) + 1;
  std::size_t n = 0;
  bool in_field = false;
  for (const char c : line) {
    const bool space = IsSpace(c) || c == '\r';
    if (!space && !in_field) ++n;
    in_field = !space;
  }
  return n;
}

bool IsBlank(std::string_view line) { return Trim(line).empty(); }

// A comment: the first byte that is not a space or tab is '#'.
bool IsComment(std::string_view line) {
  if (!line.empty() && !IsSpace(line.front())) return line.front() == '#';
  const std::size_t first = line.find_first_not_of(" \t");
  return first != std::string_view::npos && line[first] == '#';
}

// True if every field is a number (NaN and Inf included) or empty and at least one is a finite number:
// the line is data, not a header.
bool AllNumbers(const std::vector<std::string_view>& fields) {
  bool finite = false;
  for (std::string_view f : fields) {
    if (f.empty()) continue;
    if (f.front() == '+') f.remove_prefix(1);
    double v = 0;
    const auto [ptr, ec] = std::from_chars(f.data(), f.data() + f.size(), v);
    if (ptr != f.data() + f.size() || f.empty() || (ec != std::errc() && ec != std::errc::result_out_of_range))
      return false;
    finite = finite || (ec == std::errc() && std::isfinite(v));
  }
  return finite;
}

char SeparatorOf(Delimiter d) {
  switch (d) {
    case Delimiter::kSemicolon:
      return ';';
    case Delimiter::kTab:
      return '\t';
    case Delimiter::kWhitespace:
      return 0;
    default:
      return ',';
  }
}

Delimiter DelimiterOf(char separator) {
  switch (separator) {
    case ';':
      return Delimiter::kSemicolon;
    case '\t':
      return Delimiter::kTab;
    case 0:
      return Delimiter::kWhitespace;
    default:
      return Delimiter::kComma;
  }
}

// Detection (see csv.h). The one of ',', ';' and tab that splits the header; when several do, the one
// that splits the first data line (`data`, null if none) into as many fields, and when two still fit
// (or none does), both in `ambiguous` (*fits_data: whether they fit the data line). When none splits
// the header: whitespace (0) if runs of spaces split the header and the data line, else ',' (one column).
char DetectSeparator(std::string_view header, const std::string_view* data, std::pair<char, char>* ambiguous,
                     bool* fits_data) {
  *fits_data = true;
  std::vector<char> fit, splits;
  for (const char c : {',', ';', '\t'}) {
    const std::size_t h = CountFields(header, c);
    if (h > 1) splits.push_back(c);
    if (h > 1 && (data == nullptr || CountFields(*data, c) == h)) fit.push_back(c);
  }
  if (splits.size() == 1) return splits[0];  // the rows will say what does not fit
  if (splits.size() > 1) {
    if (fit.size() == 1) return fit[0];
    *fits_data = fit.size() > 1;
    *ambiguous = fit.size() > 1 ? std::pair{fit[0], fit[1]} : std::pair{splits[0], splits[1]};
    return ',';
  }
  if (CountFields(header, 0) > 1 && (data == nullptr || CountFields(*data, 0) > 1)) return 0;
  return ',';  // one column
}

// True if DetectSeparator (or the check of a given delimiter) needs the first data line: the header
// alone does not decide. Otherwise the reader reads no line ahead (a stream's header is checked as soon
// as it arrives).
bool NeedsDataLine(std::string_view header, Delimiter given) {
  if (given != Delimiter::kAuto) return CountFields(header, SeparatorOf(given)) == 1;
  int splits = 0;
  for (const char c : {',', ';', '\t'}) splits += CountFields(header, c) > 1;
  return splits > 1 || (splits == 0 && CountFields(header, 0) > 1);
}

constexpr std::size_t kShownBytes = 32;     // of a cell or name echoed in a message
constexpr std::size_t kListedColumns = 20;  // names listed by ThrowUnknownColumn
constexpr std::size_t kChunkBytes = 1 << 18;

// The bytes of `s` as a message shows them (no quotes): control bytes as \xNN, at most kShownBytes of
// them (cut at a UTF-8 character boundary) and "..." if there are more.
std::string Shown(std::string_view s) {
  std::size_t n = std::min(s.size(), kShownBytes);
  if (n < s.size())
    while (n > 0 && (static_cast<unsigned char>(s[n]) & 0xC0) == 0x80) --n;  // not inside a character
  std::string out;
  out.reserve(n + 8);
  for (const char c : s.substr(0, n)) {
    const auto u = static_cast<unsigned char>(c);
    if (u < 0x20 || u == 0x7F)
      out += fmt::format("\\x{:02x}", u);
    else
      out += c;
  }
  if (n < s.size()) out += "...";
  return out;
}

}  // namespace

std::string ShowCell(std::string_view cell) {
  if (cell.size() <= kShownBytes) return fmt::format("'{}'", Shown(cell));
  return fmt::format("'{}' ({} bytes)", Shown(cell), cell.size());
}

Delimiter ParseDelimiter(std::string_view text) {
  if (text == "auto") return Delimiter::kAuto;
  if (text == ",") return Delimiter::kComma;
  if (text == ";") return Delimiter::kSemicolon;
  if (text == "tab" || text == "\t") return Delimiter::kTab;
  if (text == "space" || text == " ") return Delimiter::kWhitespace;
  throw InvalidArgument(fmt::format("delimiter {}: need ',', ';', tab, space or auto", ShowCell(text)));
}

std::string DelimiterName(Delimiter delimiter) {
  switch (delimiter) {
    case Delimiter::kAuto:
      return "auto";
    case Delimiter::kComma:
      return "','";
    case Delimiter::kSemicolon:
      return "';'";
    case Delimiter::kTab:
      return "tab";
    case Delimiter::kWhitespace:
      return "space";
  }
  return "?";
}

[[noreturn]] void ThrowUnknownColumn(const std::string& source, std::string_view name,
                                     const std::vector<std::string>& names) {
  std::string listed;
  for (std::size_t i = 0; i < names.size() && i < kListedColumns; ++i) listed += (i ? ", " : "") + Shown(names[i]);
  if (names.size() > kListedColumns) listed += fmt::format(", ... ({} columns)", names.size());
  throw DataError(fmt::format("{}: no column '{}' (columns: {})", source, Shown(name), listed));
}

CsvReader::CsvReader(const std::string& path, const CsvOptions& options) : path_(path), options_(options) {
  if (path == kStandardInput) {  // a stream that shares standard input's buffer (not owned)
    path_ = "standard input";
    in_ = std::make_unique<std::istream>(std::cin.rdbuf());
    ReadHeader();
    return;
  }
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    throw DataError(fmt::format("cannot read '{}': it is a directory", path));
  in_ = std::make_unique<std::ifstream>(path, std::ios::in | std::ios::binary);
  if (!*in_) throw DataError(fmt::format("cannot open '{}': {}", path, std::strerror(errno)));
  internal::CountCsvFileOpened();
  ReadHeader();
}

CsvReader::CsvReader(std::unique_ptr<std::istream> in, const std::string& source, const CsvOptions& options)
    : path_(source), options_(options), in_(std::move(in)) {
  IDENT_REQUIRE(in_ != nullptr, "CSV input stream for '{}' is null", source);
  ReadHeader();
}

bool CsvReader::Fill() {
  if (chunk_.empty()) chunk_.resize(kChunkBytes);
  chunk_pos_ = chunk_end_ = 0;
  if (!*in_) return false;
  // One sgetn, which may return fewer bytes than asked for: a buffer that hands over what a pipe holds
  // (ident/io/arriving_input.h) makes each line readable as soon as it has arrived. No bytes: the end.
  std::streamsize got = 0;
  try {
    got = in_->rdbuf()->sgetn(chunk_.data(), static_cast<std::streamsize>(chunk_.size()));
  } catch (const std::exception& e) {
    throw DataError(fmt::format("cannot read '{}': {}", path_, e.what()));
  }
  if (got <= 0) {
    in_->setstate(std::ios::eofbit | std::ios::failbit);
    return false;
  }
  chunk_end_ = static_cast<std::size_t>(got);
  next_cr_ = 0;
  bytes_taken_ += static_cast<long>(got);
  if (options_.on_read) options_.on_read(bytes_taken_);
  return true;
}

std::size_t CsvReader::LineEnd() {
  // The first LF or CR at or after chunk_pos_ (chunk_end_ if none): memchr for each, with the position of
  // the next CR kept from one line to the next (a chunk without CR costs one scan for them).
  const char* const data = chunk_.data();
  if (next_cr_ < chunk_pos_ || (next_cr_ == chunk_pos_ && next_cr_ < chunk_end_ && data[next_cr_] != '\r')) {
    const void* cr = std::memchr(data + chunk_pos_, '\r', chunk_end_ - chunk_pos_);
    next_cr_ = cr ? static_cast<std::size_t>(static_cast<const char*>(cr) - data) : chunk_end_;
  }
  const void* lf = std::memchr(data + chunk_pos_, '\n', next_cr_ - chunk_pos_);
  return lf ? static_cast<std::size_t>(static_cast<const char*>(lf) - data) : next_cr_;
}

bool CsvReader::ReadLine() {
  bool carried = false;  // the line began in an earlier chunk: its bytes so far are in buffer_
  while (chunk_pos_ < chunk_end_ || Fill()) {
    if (skip_lf_) {
      skip_lf_ = false;
      if (chunk_[chunk_pos_] == '\n') {
        ++chunk_pos_;
        continue;
      }
    }
    const std::size_t stop = LineEnd();
    const std::size_t take = stop - chunk_pos_;
    const std::size_t before = carried ? buffer_.size() : 0;
    if (before + take > kMaxCsvLineBytes)
      throw DataError(fmt::format("{}:{}: line longer than {} bytes", path_, line_ + 1, kMaxCsvLineBytes));
    const char* const begin = chunk_.data() + chunk_pos_;
    if (stop == chunk_end_) {  // the line goes on in the next chunk
      if (!carried) buffer_.clear();
      buffer_.append(begin, take);
      carried = true;
      chunk_pos_ = stop;
      continue;
    }
    if (carried) {
      buffer_.append(begin, take);
      text_ = buffer_;
    } else {
      text_ = std::string_view(begin, take);  // in place: valid until the next ReadLine()
    }
    skip_lf_ = chunk_[stop] == '\r';
    chunk_pos_ = stop + 1;
    ++line_;
    return true;
  }
  if (!carried) return false;
  text_ = buffer_;
  ++line_;  // the last line, without a line end
  return true;
}

void CsvReader::ReadHeader() {
  const std::string& path = path_;
  // Header: the first line that is neither blank nor a comment.
  bool got_header = false;
  while (ReadLine()) {
    if (line_ == 1 && text_.starts_with("\xEF\xBB\xBF")) text_.remove_prefix(3);
    if (!IsBlank(text_) && !IsComment(text_)) {
      got_header = true;
      break;
    }
  }
  if (!got_header) throw DataError(fmt::format("{}: the file is empty", path));
  header_.assign(text_);
  header_line_ = line_;
  // The first data line, read ahead for the delimiter when the header does not decide it, and held for
  // Next().
  const bool read_ahead = NeedsDataLine(header_, options_.delimiter);
  while (read_ahead && ReadLine()) {
    if (!IsBlank(text_) && !IsComment(text_)) {
      held_row_.assign(text_);
      held_ = true;
      held_line_ = line_;
      break;
    }
  }
  const std::string_view data_line(held_row_);
  ChooseDelimiter(header_, held_ ? &data_line : nullptr);
  std::vector<std::string_view> fields;
  Split(header_, separator_, fields);
  if (fields.size() > static_cast<std::size_t>(kMaxCsvColumns))
    throw DataError(fmt::format("{}:{}: the header has {} columns; at most {} are supported", path, header_line_,
                                fields.size(), kMaxCsvColumns));
  if (AllNumbers(fields)) {  // no header: the line is the first row
    generated_names_ = true;
    names_.reserve(fields.size());
    for (std::size_t j = 0; j < fields.size(); ++j) names_.push_back(fmt::format("c{}", j + 1));
    header_is_row_ = true;
    return;
  }
  std::unordered_map<std::string_view, std::size_t> seen;  // name (a view into header_) -> 0-based column
  seen.reserve(fields.size());
  names_.reserve(fields.size());
  for (std::size_t j = 0; j < fields.size(); ++j) {
    std::string_view name = fields[j];
    if (name.size() >= 2 && name.front() == '"' && name.back() == '"') name = name.substr(1, name.size() - 2);
    if (name.empty()) throw DataError(fmt::format("{}:{}: column {} has an empty name", path, header_line_, j + 1));
    if (name.find('\0') != std::string_view::npos)
      throw DataError(fmt::format("{}:{}: column {} name contains a NUL byte", path, header_line_, j + 1));
    const auto [it, inserted] = seen.emplace(name, j);
    if (!inserted)
      throw DataError(fmt::format("{}:{}: duplicate column name {} (columns {} and {})", path, header_line_,
                                  ShowCell(name), it->second + 1, j + 1));
    names_.emplace_back(name);
  }
  header_.clear();
  header_.shrink_to_fit();
}

void CsvReader::ChooseDelimiter(std::string_view header, const std::string_view* data) {
  std::pair<char, char> ambiguous{0, 0};
  bool fits_data = true;
  const char detected = DetectSeparator(header, data, &ambiguous, &fits_data);
  if (options_.delimiter == Delimiter::kAuto) {
    if (ambiguous.first != 0)
      throw DataError(
          fmt::format("{}:{}: cannot tell the delimiter: {} and {} both split the header{} into several fields (pass "
                      "--delimiter)",
                      path_, header_line_, DelimiterName(DelimiterOf(ambiguous.first)),
                      DelimiterName(DelimiterOf(ambiguous.second)),
                      data && fits_data ? fmt::format(" and line {}", held_line_) : ""));
    delimiter_ = DelimiterOf(detected);
    separator_ = detected;
    return;
  }
  delimiter_ = options_.delimiter;
  separator_ = SeparatorOf(delimiter_);
  // A header of one column that another delimiter splits as it splits the first data line: a wrong
  // --delimiter.
  if (CountFields(header, separator_) == 1 && ambiguous.first == 0 && detected != separator_ &&
      CountFields(header, detected) > 1 && data != nullptr &&
      CountFields(*data, detected) == CountFields(header, detected))
    throw DataError(
        fmt::format("{}:{}: the header has one column with the delimiter {}; the file looks {}-separated (pass "
                    "--delimiter {})",
                    path_, header_line_, DelimiterName(delimiter_), DelimiterName(DelimiterOf(detected)),
                    DelimiterName(DelimiterOf(detected))));
}

int CsvReader::ColumnIndex(std::string_view name) const {
  for (std::size_t i = 0; i < names_.size(); ++i)
    if (names_[i] == name) return static_cast<int>(i);
  ThrowUnknownColumn(path_, name, names_);
}

[[gnu::always_inline]] inline double CsvReader::ParseCell(std::string_view cell, int column) const {
  // The common case inline; every problem is diagnosed by ThrowBadCell.
  // A cell with a NUL byte does not convert to its end (from_chars stops there).
  if (!cell.empty() && cell.front() != '+') {
    double value = 0;
    const auto [ptr, ec] = std::from_chars(cell.data(), cell.data() + cell.size(), value);
    if (ec == std::errc() && ptr == cell.data() + cell.size()) {
      if (std::isfinite(value)) return value;
      if (options_.missing_as_nan) return std::numeric_limits<double>::quiet_NaN();
    }
  }
  if (cell.empty() && options_.missing_as_nan) return std::numeric_limits<double>::quiet_NaN();
  return ParseUncommonCell(cell, column);
}

double CsvReader::ParseUncommonCell(std::string_view cell, int column) const {
  double value = std::numeric_limits<double>::quiet_NaN();
  if (cell.empty())
    throw DataError(
        fmt::format("{}:{}: column {} ({}) is empty (pass --missing to treat empty cells as "
                    "missing samples)",
                    path_, line_, column + 1, ShowCell(names_[column])));
  if (cell.find('\0') != std::string_view::npos)
    throw DataError(
        fmt::format("{}:{}: column {} ({}): contains a NUL byte", path_, line_, column + 1, ShowCell(names_[column])));
  std::string_view digits = cell;
  if (digits.front() == '+') digits.remove_prefix(1);
  const bool second_sign = digits.size() < cell.size() && !digits.empty() && digits.front() == '-';
  const auto [ptr, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), value);
  if (ec == std::errc::result_out_of_range)
    throw DataError(fmt::format("{}:{}: column {} ({}): {} is out of the range of double", path_, line_, column + 1,
                                ShowCell(names_[column]), ShowCell(cell)));
  if (ec != std::errc() || ptr != digits.data() + digits.size() || second_sign) {
    // A decimal comma: '1,5' in a file whose cells are not separated by commas.
    const bool decimal_comma = separator_ != ',' && cell.find(',') != std::string_view::npos;
    throw DataError(fmt::format(
        "{}:{}: column {} ({}): {} is not a number{}", path_, line_, column + 1, ShowCell(names_[column]),
        ShowCell(cell),
        decimal_comma ? fmt::format(" (the delimiter is {}: decimals take '.', not ',')", DelimiterName(delimiter_))
                      : ""));
  }
  if (!std::isfinite(value)) {
    if (!options_.missing_as_nan)
      throw DataError(
          fmt::format("{}:{}: column {} ({}): {} is not a finite number (pass --missing to "
                      "treat NaN/Inf/empty cells as missing samples)",
                      path_, line_, column + 1, ShowCell(names_[column]), ShowCell(cell)));
    value = std::numeric_limits<double>::quiet_NaN();
  }
  return value;  // '+' followed by a finite number
}

bool CsvReader::ParsePlainRow(std::string_view text, Eigen::Ref<Eigen::VectorXd> row) const {
  // Each cell converted from where the previous one ended: the number must end at the separator (or the
  // line's end) and be finite. Anything else (spaces, '+', an empty, bad or non-finite cell, a wrong
  // number of fields) is left to ParseRow's general walk, which reads the same cells to the same values.
  const char* p = text.data();
  const char* const end = p + text.size();
  const int n = num_columns();
  for (int column = 0; column < n; ++column) {
    double value = 0;
    const auto [ptr, ec] = std::from_chars(p, end, value);
    if (ec != std::errc() || ptr == p || !std::isfinite(value)) return false;
    if (ptr == end) {
      if (column + 1 != n) return false;
    } else if (*ptr != separator_ || column + 1 == n) {
      return false;
    }
    row(column) = value;
    p = ptr + 1;
  }
  return true;
}

void CsvReader::ParseRow(std::string_view text, Eigen::Ref<Eigen::VectorXd> row) {
  if (separator_ != 0 && ParsePlainRow(text, row)) return;
  // Parse in place without allocating: walk the fields.
  const int n = num_columns();
  int column = 0;
  if (separator_ == 0) {  // runs of spaces and tabs
    std::size_t pos = 0;
    while (true) {
      while (pos < text.size() && IsSpace(text[pos])) ++pos;
      if (pos == text.size()) break;
      std::size_t end = pos;
      while (end < text.size() && !IsSpace(text[end])) ++end;
      if (column >= n)
        throw DataError(fmt::format("{}:{}: row has {} fields; the header has {}", path_, line_,
                                    column + CountFields(text.substr(pos), 0), n));
      row(column) = ParseCell(text.substr(pos, end - pos), column);
      ++column;
      pos = end;
    }
  } else {
    std::string_view rest = text;
    while (true) {
      const std::size_t at = rest.find(separator_);
      if (column >= n)
        throw DataError(fmt::format("{}:{}: row has {} fields; the header has {}", path_, line_,
                                    column + CountFields(rest, separator_), n));
      row(column) = ParseCell(Trim(rest.substr(0, at)), column);
      ++column;
      if (at == std::string_view::npos) break;
      rest.remove_prefix(at + 1);
    }
  }
  if (column != n)
    throw DataError(
        fmt::format("{}:{}: row has {} field{}; the header has {}", path_, line_, column, column == 1 ? "" : "s", n));
}

bool CsvReader::Next(Eigen::Ref<Eigen::VectorXd> row) {
  IDENT_REQUIRE(row.size() == num_columns(), "row has {} entries; the file has {} columns", row.size(), num_columns());
  if (header_is_row_ || held_) {  // lines read with the header
    if (header_is_row_) {
      header_is_row_ = false;
      line_ = header_line_;
      ParseRow(header_, row);
      header_.clear();
      header_.shrink_to_fit();
    } else {
      held_ = false;
      line_ = held_line_;
      ParseRow(held_row_, row);
    }
    ++rows_;
    return true;
  }
  while (ReadLine()) {
    if (IsBlank(text_)) {
      if (rows_ > 0 && blank_line_ == 0) blank_line_ = line_;
      continue;
    }
    if (IsComment(text_)) continue;
    if (blank_line_ != 0)
      throw DataError(fmt::format("{}:{}: blank line inside the data (a gap in the record?)", path_, blank_line_));
    ParseRow(text_, row);
    ++rows_;
    return true;
  }
  if (rows_ == 0) throw DataError(fmt::format("{}: no data rows after the header", path_));
  return false;
}

long DataTable::Line(int row) const {
  const auto after = std::upper_bound(row_lines.begin(), row_lines.end(), row,
                                      [](int r, const std::pair<int, long>& p) { return r < p.first; });
  if (after == row_lines.begin()) return 0;
  const auto& [first, line] = *(after - 1);
  return line + (row - first);
}

int DataTable::ColumnIndex(std::string_view name) const {
  for (std::size_t i = 0; i < names.size(); ++i)
    if (names[i] == name) return static_cast<int>(i);
  ThrowUnknownColumn(source, name, names);
}

bool DataTable::StartsExperiment(int row) const {
  return std::binary_search(experiment_starts.begin(), experiment_starts.end(), row);
}

namespace {

DataTable ReadAll(CsvReader& reader) {
  DataTable table;
  table.source = reader.path();
  table.names = reader.names();
  table.generated_names = reader.generated_names();
  const int n = reader.num_columns();
  std::vector<double> data;
  Eigen::VectorXd row(n);
  long last_line = -1;
  for (int r = 0; reader.Next(row); ++r) {
    data.insert(data.end(), row.data(), row.data() + n);
    if (reader.line() != last_line + 1) table.row_lines.emplace_back(r, reader.line());
    last_line = reader.line();
  }
  const Eigen::Index rows = static_cast<Eigen::Index>(data.size()) / n;
  table.values =
      Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(data.data(), rows, n);
  return table;
}

}  // namespace

namespace {
std::atomic<long> csv_files_opened{0};
}  // namespace

long CsvFilesOpened() { return csv_files_opened.load(); }
void internal::CountCsvFileOpened() { ++csv_files_opened; }

bool CanReadTwice(const std::string& path) {
  std::error_code ec;
  return path != kStandardInput && std::filesystem::is_regular_file(path, ec);
}

DataTable ReadCsv(const std::string& path, const CsvOptions& options) {
  CsvReader reader(path, options);
  return ReadAll(reader);
}

DataTable ParseCsv(std::string_view text, const std::string& source, const CsvOptions& options) {
  CsvReader reader(std::make_unique<std::istringstream>(std::string(text)), source, options);
  return ReadAll(reader);
}

}  // namespace ident::io
