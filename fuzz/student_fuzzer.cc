// libFuzzer target: Kárný–Hangos Student-t / Cauchy regression fed arbitrary doubles (properties in
// fuzz/student_property.h).
#include "fuzz/fuzz_util.h"
#include "fuzz/student_property.h"

IDENT_FUZZ_ENTRY(ident::fuzz::StudentProperty)
