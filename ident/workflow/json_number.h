// A number for the JSON reports: the value when finite, null otherwise (JSON has no NaN or infinity).
#pragma once

#include <cmath>

#include <nlohmann/json.hpp>

namespace ident::workflow {

inline nlohmann::ordered_json FiniteOrNull(double v) {
  return std::isfinite(v) ? nlohmann::ordered_json(v) : nlohmann::ordered_json();
}

}  // namespace ident::workflow
