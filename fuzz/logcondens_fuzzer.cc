// libFuzzer target: the log-concave MLE on arbitrary samples (properties in fuzz/logcondens_property.h).
#include "fuzz/fuzz_util.h"
#include "fuzz/logcondens_property.h"

IDENT_FUZZ_ENTRY(ident::fuzz::LogcondensProperty)
