// libFuzzer target: the MODEL.json reader of `ident smooth` and the MAP smoother on what it accepts
// (properties in fuzz/smooth_model_property.h).
#include "fuzz/fuzz_util.h"
#include "fuzz/smooth_model_property.h"

IDENT_FUZZ_ENTRY(ident::fuzz::SmoothModelProperty)
