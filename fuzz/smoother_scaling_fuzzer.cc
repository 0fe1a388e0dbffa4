// libFuzzer target: the MAP smoother on a problem and on the same problem in another unit and origin
// (property in fuzz/smoother_scaling_property.h).
#include "fuzz/fuzz_util.h"
#include "fuzz/smoother_scaling_property.h"

IDENT_FUZZ_ENTRY(ident::fuzz::SmootherScalingProperty)
