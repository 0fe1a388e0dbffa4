// The text of a CSV line as the reader (ident/io/csv.h) walks it: trimming, field counts, blank and comment
// lines; shared by the header and delimiter detection and the row parsing.
#pragma once

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstddef>
#include <string_view>

namespace ident::io {
enum class Delimiter;  // csv.h
}  // namespace ident::io

namespace ident::io::internal {

// The delimiter's character; 0 for runs of spaces and tabs.
char SeparatorOf(Delimiter delimiter);

inline std::string_view Trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) s.remove_suffix(1);
  return s;
}

inline bool IsSpace(char c) { return c == ' ' || c == '\t'; }

// The number of fields `line` splits into at `separator` (0: runs of spaces and tabs).
inline std::size_t CountFields(std::string_view line, char separator) {
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

inline bool IsBlank(std::string_view line) { return Trim(line).empty(); }

// A comment: the first byte that is not a space or tab is '#'.
inline bool IsComment(std::string_view line) {
  if (!line.empty() && !IsSpace(line.front())) return line.front() == '#';
  const std::size_t first = line.find_first_not_of(" \t");
  return first != std::string_view::npos && line[first] == '#';
}

// The fast path of a row: the n cells of [p, end) converted into out[0..n), each from where the previous
// one ended; every number must end at `separator` (the last at `end`) and be finite. False for anything
// else (spaces, '+', an empty, bad or non-finite cell, a wrong number of fields), which the reader's
// general walk then takes; out[] may then hold some of the row's values.
inline bool ParsePlainFields(const char* p, const char* const end, char separator, int n, double* out) {
  for (int column = 0; column < n; ++column) {
    double value = 0;
    const auto [ptr, ec] = std::from_chars(p, end, value);
    if (ec != std::errc() || ptr == p || !std::isfinite(value)) return false;
    if (ptr == end) {
      if (column + 1 != n) return false;
    } else if (*ptr != separator || column + 1 == n) {
      return false;
    }
    out[column] = value;
    p = ptr + 1;
  }
  return true;
}

}  // namespace ident::io::internal
