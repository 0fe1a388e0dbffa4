// libFuzzer target: output files written through a temporary file and renamed on success, with
// simulated failures, and the trace rows of `ident fit` read back (properties in fuzz/output_file_property.h).
#include "fuzz/fuzz_util.h"
#include "fuzz/output_file_property.h"

IDENT_FUZZ_ENTRY(ident::fuzz::OutputFileProperty)
