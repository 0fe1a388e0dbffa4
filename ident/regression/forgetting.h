// Forgetting options shared by the regression estimators [spec §7b].
#pragma once

#include <string>

namespace ident {

struct ForgettingOptions {
  double factor = 1.0;      // λ ∈ (0, 1]; 1 = no forgetting
  bool stabilised = false;  // false: exponential (ν̃ = λν); true: stabilised towards the prior (ν0, V0)

  // "" if valid, else one line naming the option, e.g. "forgetting = 1.2; need 0 < forgetting <= 1".
  std::string Validate() const;
};

}  // namespace ident
