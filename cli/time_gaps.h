// The one-line report of a record's time-column gaps (ident/workflow/time_column.h), shared by the
// commands that check the time column.
#pragma once

#include <cstdio>

#include "ident/workflow/time_column.h"

namespace ident::cli {

// "time column 't': 2 gaps (...): row 41 (4 -> 4.3), ..." with the first five gaps; `filled` says whether
// --missing filled them. Prints nothing without gaps.
void PrintTimeGaps(std::FILE* out, const workflow::TimeCheck& time, bool filled);

}  // namespace ident::cli
