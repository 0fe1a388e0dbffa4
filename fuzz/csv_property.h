// Property of the CSV reader (ident::io::ParseCsv / CsvReader) on arbitrary text.
// Input: 1 byte (bit 0 = missing_as_nan), then the text.
// Holds if: nothing but ident::DataError is thrown, and a returned table has unique non-empty column
// names, at least one row, and only finite cells (or NaN = missing when missing_as_nan is set).
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <set>
#include <string>
#include <string_view>

#include "ident/common/error.h"
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
    for (const auto& name : table.names)
      if (name.empty()) return "column names are not empty";
    for (Eigen::Index i = 0; i < table.values.size(); ++i) {
      const double v = table.values.data()[i];
      if (!(std::isfinite(v) || (options.missing_as_nan && std::isnan(v))))
        return "cells are finite (or NaN = missing with missing_as_nan)";
    }
  } catch (const DataError&) {
    // the expected answer to bad text: a located one-line message
  }
  return {};
}

}  // namespace ident::fuzz
