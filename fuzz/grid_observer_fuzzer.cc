// libFuzzer target: the grid Bayesian observer fed arbitrary models and readings (properties in
// fuzz/grid_observer_property.h).
#include "fuzz/fuzz_util.h"
#include "fuzz/grid_observer_property.h"

IDENT_FUZZ_ENTRY(ident::fuzz::GridObserverProperty)
