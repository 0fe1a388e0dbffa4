// The registry's refusal of a spec, as text: what the registry tests compare with the expected message.
#pragma once

#include <string>

#include "common/error.h"
#include "ident/registry/estimator_registry.h"

namespace ident::testing {

// The InvalidArgument message of MakeEstimator(ParseEstimatorSpec(spec), problem) (a RegressionProblem or an
// ObserverProblem), or "(no error)".
template <class Problem>
std::string SpecError(const std::string& spec, const Problem& problem) {
  try {
    MakeEstimator(ParseEstimatorSpec(spec), problem);
  } catch (const InvalidArgument& e) {
    return e.what();
  }
  return "(no error)";
}

}  // namespace ident::testing
