// The CSV reader (ident/io/csv.h): lines read in chunks, rows parsed in place to numbers, whole tables.
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

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "common/error.h"
#include "ident/io/internal/csv_text.h"

namespace ident::io {

using internal::CountFields;
using internal::IsBlank;
using internal::IsComment;
using internal::IsSpace;
using internal::Trim;

namespace {

constexpr std::size_t kChunkBytes = 1 << 18;

}  // namespace

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
  std::streamsize got = 0, want = static_cast<std::streamsize>(chunk_.size());
  if (options_.prefix_bytes >= 0) want = std::min<std::streamsize>(want, options_.prefix_bytes - bytes_taken_);
  try {
    if (want > 0) got = in_->rdbuf()->sgetn(chunk_.data(), want);
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
  if (options_.on_bytes) options_.on_bytes(std::string_view(chunk_.data(), chunk_end_));
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

[[gnu::always_inline]] inline double CsvReader::ParseCell(std::string_view cell, int column) const {
  // The common case inline; every problem is diagnosed by ParseUncommonCell.
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
  // Anything but plain cells is left to ParseRow's general walk, which reads the same cells to the same
  // values.
  return internal::ParsePlainFields(text.data(), text.data() + text.size(), separator_, num_columns(), row.data());
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

// The reader's rows as a table; std::nullopt once it has read more than `max_rows`.
std::optional<DataTable> ReadRows(CsvReader& reader, long max_rows) {
  DataTable table;
  table.source = reader.path();
  table.names = reader.names();
  table.generated_names = reader.generated_names();
  const int n = reader.num_columns();
  std::vector<double> data;
  Eigen::VectorXd row(n);
  long last_line = -1;
  for (long r = 0; reader.Next(row); ++r) {
    if (r == max_rows) return std::nullopt;
    data.insert(data.end(), row.data(), row.data() + n);
    if (reader.line() != last_line + 1) table.row_lines.emplace_back(static_cast<int>(r), reader.line());
    last_line = reader.line();
  }
  const Eigen::Index rows = static_cast<Eigen::Index>(data.size()) / n;
  table.values =
      Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(data.data(), rows, n);
  return table;
}

DataTable ReadAll(CsvReader& reader) { return *ReadRows(reader, std::numeric_limits<long>::max()); }

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
  return *ReadCsvUpTo(path, std::numeric_limits<long>::max(), options);
}

std::optional<DataTable> ReadCsvUpTo(const std::string& path, long max_rows, const CsvOptions& options) {
  CsvReader reader(path, options);
  return ReadRows(reader, max_rows);
}

DataTable ParseCsv(std::string_view text, const std::string& source, const CsvOptions& options) {
  CsvReader reader(std::make_unique<std::istringstream>(std::string(text)), source, options);
  return ReadAll(reader);
}

}  // namespace ident::io
