// libFuzzer target: the CSV reader on arbitrary text (properties in fuzz/csv_property.h).
#include "fuzz/csv_property.h"
#include "fuzz/fuzz_util.h"

IDENT_FUZZ_ENTRY(ident::fuzz::CsvProperty)
