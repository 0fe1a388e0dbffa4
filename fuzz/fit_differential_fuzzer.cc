// libFuzzer target: workflow::Fit against workflow::FitCsvFile, and a record against the same record in other
// units, for every registered estimator (properties in fuzz/fit_differential_property.h).
#include "fuzz/fit_differential_property.h"
#include "fuzz/fuzz_util.h"

IDENT_FUZZ_ENTRY(ident::fuzz::FitDifferentialProperty)
