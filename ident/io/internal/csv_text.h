// The text of a CSV line as the reader (ident/io/csv.h) walks it: trimming, field counts, blank and comment
// lines; shared by the header and delimiter detection and the row parsing.
#pragma once

#include <algorithm>
#include <cstddef>
#include <string_view>

namespace ident::io::internal {

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

}  // namespace ident::io::internal
