// libFuzzer target: the log-concave Gaussian filter fed arbitrary doubles (properties in fuzz/observer_property.h).
#include "fuzz/fuzz_util.h"
#include "fuzz/observer_property.h"

IDENT_FUZZ_ENTRY(ident::fuzz::LcGaussianProperty)
