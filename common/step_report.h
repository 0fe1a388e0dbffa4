// What one recursive update did. Trivially copyable, no strings: safe in real-time loops.
//
// Every recursive estimator's Update() returns a StepReport. The status says whether the
// estimator's state changed; the numbers describe the step (for regression estimators: the
// weight β(t) given to the sample, the sample count ν(t) and the one-step prediction error
// ê(t) = y(t) − Θ̂(t−1)'z(t), computed before the update).
#pragma once

#include <limits>
#include <string_view>

namespace ident {

enum class StepStatus {
  kUpdated,           // the state changed
  kSkipped,           // the caller skipped the sample (disabled or missing); state unchanged
  kRejectedInvalid,   // the sample had NaN/Inf, wrong size or would overflow; state unchanged
  kNumericalFailure,  // the step would have broken an invariant (e.g. D not positive); state unchanged
};

constexpr std::string_view ToString(StepStatus status) {
  switch (status) {
    case StepStatus::kUpdated:
      return "updated";
    case StepStatus::kSkipped:
      return "skipped";
    case StepStatus::kRejectedInvalid:
      return "rejected (invalid sample)";
    case StepStatus::kNumericalFailure:
      return "rejected (numerical failure)";
  }
  return "unknown";
}

struct StepReport {
  StepStatus status = StepStatus::kUpdated;
  double weight = std::numeric_limits<double>::quiet_NaN();            // β(t)
  double nu = std::numeric_limits<double>::quiet_NaN();                // ν(t)
  double prediction_error = std::numeric_limits<double>::quiet_NaN();  // ê(t), before the update
  bool updated() const { return status == StepStatus::kUpdated; }
};

}  // namespace ident
