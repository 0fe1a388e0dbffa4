#include "ident/io/csv.h"

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <limits>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "ident/common/error.h"

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

}  // namespace

[[noreturn]] void ThrowUnknownColumn(const std::string& source, std::string_view name,
                                     const std::vector<std::string>& names) {
  throw DataError(fmt::format("{}: no column '{}' (columns: {})", source, name, fmt::join(names, ", ")));
}

CsvReader::CsvReader(const std::string& path, const CsvOptions& options) : path_(path), options_(options) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) throw DataError(fmt::format("cannot read '{}': it is a directory", path));
  in_ = std::make_unique<std::ifstream>(path, std::ios::in | std::ios::binary);
  if (!*in_) throw DataError(fmt::format("cannot open '{}': {}", path, std::strerror(errno)));
  ReadHeader();
}

CsvReader::CsvReader(std::unique_ptr<std::istream> in, const std::string& source, const CsvOptions& options)
    : path_(source), options_(options), in_(std::move(in)) {
  IDENT_REQUIRE(in_ != nullptr, "CSV input stream for '{}' is null", source);
  ReadHeader();
}

void CsvReader::ReadHeader() {
  const std::string& path = path_;
  // Header: the first non-blank line.
  bool got_header = false;
  while (std::getline(*in_, buffer_)) {
    ++line_;
    if (line_ == 1 && buffer_.starts_with("\xEF\xBB\xBF")) buffer_.erase(0, 3);
    if (!IsBlank(buffer_)) {
      got_header = true;
      break;
    }
  }
  if (!got_header) {
    if (in_->bad()) throw DataError(fmt::format("cannot read '{}': {}", path, std::strerror(errno)));
    throw DataError(fmt::format("{}: the file is empty", path));
  }
  std::vector<std::string_view> fields;
  Split(buffer_, fields);
  for (std::size_t j = 0; j < fields.size(); ++j) {
    std::string_view name = fields[j];
    if (name.size() >= 2 && name.front() == '"' && name.back() == '"') name = name.substr(1, name.size() - 2);
    if (name.empty()) throw DataError(fmt::format("{}:{}: column {} has an empty name", path, line_, j + 1));
    for (std::size_t i = 0; i < names_.size(); ++i)
      if (names_[i] == name)
        throw DataError(fmt::format("{}:{}: duplicate column name '{}' (columns {} and {})", path, line_, name,
                                    i + 1, j + 1));
    names_.emplace_back(name);
  }
}

int CsvReader::ColumnIndex(std::string_view name) const {
  for (std::size_t i = 0; i < names_.size(); ++i)
    if (names_[i] == name) return static_cast<int>(i);
  ThrowUnknownColumn(path_, name, names_);
}

bool CsvReader::Next(Eigen::Ref<Eigen::VectorXd> row) {
  IDENT_REQUIRE(row.size() == num_columns(), "row has {} entries; the file has {} columns", row.size(),
                num_columns());
  while (std::getline(*in_, buffer_)) {
    ++line_;
    if (IsBlank(buffer_)) continue;
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
          throw DataError(fmt::format("{}:{}: column {} ('{}') is empty (pass --missing to treat empty cells as "
                                      "missing samples)",
                                      path_, line_, column + 1, names_[column]));
      } else {
        std::string_view digits = cell;
        if (digits.front() == '+') digits.remove_prefix(1);
        const auto [ptr, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), value);
        if (ec == std::errc::result_out_of_range)
          throw DataError(fmt::format("{}:{}: column {} ('{}'): '{}' is out of the range of double", path_, line_,
                                      column + 1, names_[column], cell));
        if (ec != std::errc() || ptr != digits.data() + digits.size())
          throw DataError(fmt::format("{}:{}: column {} ('{}'): '{}' is not a number", path_, line_, column + 1,
                                      names_[column], cell));
        if (!std::isfinite(value)) {
          if (!options_.missing_as_nan)
            throw DataError(fmt::format("{}:{}: column {} ('{}'): '{}' is not a finite number (pass --missing to "
                                        "treat NaN/Inf/empty cells as missing samples)",
                                        path_, line_, column + 1, names_[column], cell));
          value = std::numeric_limits<double>::quiet_NaN();
        }
      }
      row(column++) = value;
      if (comma == std::string_view::npos) break;
      rest.remove_prefix(comma + 1);
    }
    if (column != n)
      throw DataError(fmt::format("{}:{}: row has {} field{}; the header has {}", path_, line_, column,
                                  column == 1 ? "" : "s", n));
    ++rows_;
    return true;
  }
  if (in_->bad()) throw DataError(fmt::format("{}:{}: read error", path_, line_));
  if (rows_ == 0) throw DataError(fmt::format("{}: no data rows after the header", path_));
  return false;
}

int DataTable::ColumnIndex(std::string_view name) const {
  for (std::size_t i = 0; i < names.size(); ++i)
    if (names[i] == name) return static_cast<int>(i);
  ThrowUnknownColumn(source, name, names);
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
  table.values = Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(data.data(), rows, n);
  return table;
}

}  // namespace

DataTable ReadCsv(const std::string& path, const CsvOptions& options) {
  CsvReader reader(path, options);
  return ReadAll(reader);
}

DataTable ParseCsv(std::string_view text, const std::string& source, const CsvOptions& options) {
  CsvReader reader(std::make_unique<std::istringstream>(std::string(text)), source, options);
  return ReadAll(reader);
}

}  // namespace ident::io
