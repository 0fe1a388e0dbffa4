#include "ident/regression/rls.h"

#include <fmt/core.h>

namespace ident {

std::string RlsOptions::Validate(int num_parameters) const {
  if (num_parameters < 1) return fmt::format("number of parameters = {}; need at least 1", num_parameters);
  if (std::string e = forgetting.Validate(); !e.empty()) return e;
  if (prior) {
    if (prior->num_parameters() != num_parameters)
      return fmt::format("prior matrix V0 is {}x{}; need {}x{} for {} parameters", prior->V0.rows(), prior->V0.cols(),
                         num_parameters + 1, num_parameters + 1, num_parameters);
    try {
      prior->Validate();
    } catch (const InvalidArgument& e) {
      return e.what();
    }
  }
  return {};
}

}  // namespace ident
