#include "ident/io/csv.h"

#include <algorithm>
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

// Splits on commas into `fields` (views into `line`).
void Split(std::string_view line, std::vector<std::string_view>& fields) {
  fields.clear();
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = line.find(',', start);
    fields.push_back(Trim(line.substr(start, comma == std::string_view::npos ? comma : comma - start)));
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
}

bool IsBlank(std::string_view line) { return Trim(line).empty(); }

constexpr std::size_t kShownBytes = 32;     // of a cell or name echoed in a message
constexpr std::size_t kListedColumns = 20;  // names listed by ThrowUnknownColumn
constexpr std::size_t kChunkBytes = 1 << 16;

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
  return true;
}

bool CsvReader::ReadLine() {
  buffer_.clear();
  bool started = false;  // a byte of the line (or its end) was read
  while (chunk_pos_ < chunk_end_ || Fill()) {
    if (skip_lf_) {
      skip_lf_ = false;
      if (chunk_[chunk_pos_] == '\n') {
        ++chunk_pos_;
        continue;
      }
    }
    started = true;
    const char* const begin = chunk_.data() + chunk_pos_;
    const char* const end = chunk_.data() + chunk_end_;
    const char* const stop = std::find_if(begin, end, [](char c) { return c == '\n' || c == '\r'; });
    const auto take = static_cast<std::size_t>(stop - begin);
    if (buffer_.size() + take > kMaxCsvLineBytes)
      throw DataError(fmt::format("{}:{}: line longer than {} bytes", path_, line_ + 1, kMaxCsvLineBytes));
    buffer_.append(begin, take);
    chunk_pos_ += take;
    if (stop != end) {
      skip_lf_ = *stop == '\r';
      ++chunk_pos_;
      ++line_;
      return true;
    }
  }
  if (!started) return false;
  ++line_;  // the last line, without a line end
  return true;
}

void CsvReader::ReadHeader() {
  const std::string& path = path_;
  // Header: the first non-blank line.
  bool got_header = false;
  while (ReadLine()) {
    if (line_ == 1 && buffer_.starts_with("\xEF\xBB\xBF")) buffer_.erase(0, 3);
    if (!IsBlank(buffer_)) {
      got_header = true;
      break;
    }
  }
  if (!got_header) throw DataError(fmt::format("{}: the file is empty", path));
  std::vector<std::string_view> fields;
  Split(buffer_, fields);
  if (fields.size() > static_cast<std::size_t>(kMaxCsvColumns))
    throw DataError(fmt::format("{}:{}: the header has {} columns; at most {} are supported", path, line_,
                                fields.size(), kMaxCsvColumns));
  std::unordered_map<std::string_view, std::size_t> seen;  // name (a view into buffer_) -> 0-based column
  seen.reserve(fields.size());
  names_.reserve(fields.size());
  for (std::size_t j = 0; j < fields.size(); ++j) {
    std::string_view name = fields[j];
    if (name.size() >= 2 && name.front() == '"' && name.back() == '"') name = name.substr(1, name.size() - 2);
    if (name.empty()) throw DataError(fmt::format("{}:{}: column {} has an empty name", path, line_, j + 1));
    if (name.find('\0') != std::string_view::npos)
      throw DataError(fmt::format("{}:{}: column {} name contains a NUL byte", path, line_, j + 1));
    const auto [it, inserted] = seen.emplace(name, j);
    if (!inserted)
      throw DataError(fmt::format("{}:{}: duplicate column name {} (columns {} and {})", path, line_, ShowCell(name),
                                  it->second + 1, j + 1));
    names_.emplace_back(name);
  }
}

int CsvReader::ColumnIndex(std::string_view name) const {
  for (std::size_t i = 0; i < names_.size(); ++i)
    if (names_[i] == name) return static_cast<int>(i);
  ThrowUnknownColumn(path_, name, names_);
}

bool CsvReader::Next(Eigen::Ref<Eigen::VectorXd> row) {
  IDENT_REQUIRE(row.size() == num_columns(), "row has {} entries; the file has {} columns", row.size(), num_columns());
  while (ReadLine()) {
    if (IsBlank(buffer_)) {
      if (rows_ > 0 && blank_line_ == 0) blank_line_ = line_;
      continue;
    }
    if (blank_line_ != 0)
      throw DataError(fmt::format("{}:{}: blank line inside the data (a gap in the record?)", path_, blank_line_));
    // Parse in place without allocating: walk the fields.
    std::string_view rest(buffer_);
    int column = 0;
    const int n = num_columns();
    while (true) {
      const std::size_t comma = rest.find(',');
      const std::string_view cell = Trim(rest.substr(0, comma));
      if (column >= n) {
        int fields = column + 1;
        for (std::size_t p = comma; p != std::string_view::npos; p = rest.find(',', p + 1)) ++fields;
        throw DataError(fmt::format("{}:{}: row has {} fields; the header has {}", path_, line_, fields, n));
      }
      double value = std::numeric_limits<double>::quiet_NaN();
      if (cell.empty()) {
        if (!options_.missing_as_nan)
          throw DataError(
              fmt::format("{}:{}: column {} ({}) is empty (pass --missing to treat empty cells as "
                          "missing samples)",
                          path_, line_, column + 1, ShowCell(names_[column])));
      } else {
        if (cell.find('\0') != std::string_view::npos)
          throw DataError(fmt::format("{}:{}: column {} ({}): contains a NUL byte", path_, line_, column + 1,
                                      ShowCell(names_[column])));
        std::string_view digits = cell;
        if (digits.front() == '+') digits.remove_prefix(1);
        const bool second_sign = digits.size() < cell.size() && !digits.empty() && digits.front() == '-';
        const auto [ptr, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), value);
        if (ec == std::errc::result_out_of_range)
          throw DataError(fmt::format("{}:{}: column {} ({}): {} is out of the range of double", path_, line_,
                                      column + 1, ShowCell(names_[column]), ShowCell(cell)));
        if (ec != std::errc() || ptr != digits.data() + digits.size() || second_sign)
          throw DataError(fmt::format("{}:{}: column {} ({}): {} is not a number", path_, line_, column + 1,
                                      ShowCell(names_[column]), ShowCell(cell)));
        if (!std::isfinite(value)) {
          if (!options_.missing_as_nan)
            throw DataError(
                fmt::format("{}:{}: column {} ({}): {} is not a finite number (pass --missing to "
                            "treat NaN/Inf/empty cells as missing samples)",
                            path_, line_, column + 1, ShowCell(names_[column]), ShowCell(cell)));
          value = std::numeric_limits<double>::quiet_NaN();
        }
      }
      row(column++) = value;
      if (comma == std::string_view::npos) break;
      rest.remove_prefix(comma + 1);
    }
    if (column != n)
      throw DataError(
          fmt::format("{}:{}: row has {} field{}; the header has {}", path_, line_, column, column == 1 ? "" : "s", n));
    ++rows_;
    return true;
  }
  if (rows_ == 0) throw DataError(fmt::format("{}: no data rows after the header", path_));
  return false;
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
  const int n = reader.num_columns();
  std::vector<double> data;
  Eigen::VectorXd row(n);
  while (reader.Next(row)) data.insert(data.end(), row.data(), row.data() + n);
  const Eigen::Index rows = static_cast<Eigen::Index>(data.size()) / n;
  table.values =
      Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(data.data(), rows, n);
  return table;
}

}  // namespace

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
