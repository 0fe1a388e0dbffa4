// Property of the CSV reader (ident::io::ParseCsv / CsvReader) on arbitrary text.
// Input: 1 byte (bit 0 = missing_as_nan), then the text.
// Holds if: nothing but ident::DataError is thrown, its message is one line of at most 512 bytes with
// no NUL byte (cells are shown truncated and escaped), and a returned table has unique non-empty column
// names without line-end or NUL bytes (LF, CRLF and CR all end lines), at least one row, and only
// finite cells (or NaN = missing when missing_as_nan is set).
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <set>
#include <string>
#include <string_view>

#include "common/error.h"
#include "ident/io/csv.h"

namespace ident::fuzz {

inline std::string CsvProperty(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return {};
  io::CsvOptions options;
  options.missing_as_nan = (data[0] & 1) != 0;
  const std::string_view text(reinterpret_cast<const char*>(data + 1), size - 1);
  try {
    const io::DataTable table = io::ParseCsv(text, "<fuzz>", options);
    if (table.num_rows() < 1) return "a table has at least one row";
    if (static_cast<std::size_t>(table.values.cols()) != table.names.size()) return "one column per name";
    if (std::set<std::string>(table.names.begin(), table.names.end()).size() != table.names.size())
      return "column names are unique";
    for (const auto& name : table.names) {
      if (name.empty()) return "column names are not empty";
      if (name.find_first_of(std::string_view("\r\n\0", 3)) != std::string::npos)
        return "column names hold no CR, LF or NUL byte";
    }
    for (Eigen::Index i = 0; i < table.values.size(); ++i) {
      const double v = table.values.data()[i];
      if (!(std::isfinite(v) || (options.missing_as_nan && std::isnan(v))))
        return "cells are finite (or NaN = missing with missing_as_nan)";
    }
  } catch (const DataError& e) {
    // the expected answer to bad text: a located one-line message
    const std::string_view message(e.what());
    if (message.find_first_of(std::string_view("\r\n\0", 3)) != std::string_view::npos)
      return "a message is one line without NUL bytes";
    if (message.size() > 512) return "a message is at most 512 bytes";
  }
  return {};
}

}  // namespace ident::fuzz
