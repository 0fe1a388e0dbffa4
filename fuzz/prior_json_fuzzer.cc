// libFuzzer target: the prior JSON reader on arbitrary bytes (properties in fuzz/prior_json_property.h).
#include "fuzz/fuzz_util.h"
#include "fuzz/prior_json_property.h"

IDENT_FUZZ_ENTRY(ident::fuzz::PriorJsonProperty)
