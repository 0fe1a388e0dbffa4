// The row count of ident/workflow/fit.h with its two-thread threshold as a parameter, so that tests can cut small
// files in two (internal to ident/workflow/).
#pragma once

#include <string>

namespace ident::workflow::internal {

// Files of at least this many bytes are counted on two threads by CountCsvDataRows.
inline constexpr long kTwoThreadRowCountBytes = 2L << 20;

// CountCsvDataRows(path), counting a regular file of `two_thread_bytes` or more in two halves at once.
long CountCsvDataRows(const std::string& path, long two_thread_bytes);

}  // namespace ident::workflow::internal
