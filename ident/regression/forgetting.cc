#include "ident/regression/forgetting.h"

#include <cmath>

#include <fmt/core.h>

namespace ident {

std::string ForgettingOptions::Validate() const {
  if (!(std::isfinite(factor) && factor > 0 && factor <= 1))
    return fmt::format("forgetting = {}; need 0 < forgetting <= 1", factor);
  return {};
}

}  // namespace ident
