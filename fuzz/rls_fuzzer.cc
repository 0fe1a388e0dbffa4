// libFuzzer target: LD-form RLS fed arbitrary doubles (properties in fuzz/rls_property.h).
#include "fuzz/fuzz_util.h"
#include "fuzz/rls_property.h"

IDENT_FUZZ_ENTRY(ident::fuzz::RlsProperty)
