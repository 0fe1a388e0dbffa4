// The row count of ident/workflow/fit.h in parts: with its two-thread threshold as a parameter, so that tests
// can cut small files in two, and from a byte offset on, for the first pass of a streamed fit (internal to
// ident/workflow/).
#pragma once

#include <string>

namespace ident::workflow::internal {

// Files of at least this many bytes are counted on two threads by CountCsvDataRows.
inline constexpr long kTwoThreadRowCountBytes = 2L << 20;

// CountCsvDataRows(path), counting a regular file of `two_thread_bytes` or more in two halves at once.
long CountCsvDataRows(const std::string& path, long two_thread_bytes);

// Where a line of the regular file `path` starts at or past byte `at`: just after the first LF at or past it
// (the lines before and from there count apart what the whole counts); 0 if there is none within a line's
// length limit, or the file is not regular.
long CsvLineStartFrom(const std::string& path, long at);

// The lines of the regular file `path` from byte `begin` (which starts a line) to its end, as CountCsvDataRows
// counts them (blank and comment lines skipped; no header taken off).
long CountCsvLinesFrom(const std::string& path, long begin);

}  // namespace ident::workflow::internal
