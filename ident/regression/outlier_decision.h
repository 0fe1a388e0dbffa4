// When does a recursive estimator's own step say "this sample was an outlier"?
//
// Every regression estimator reports the weight β(t) it gave the sample and its sample count ν(t)
// (common/step_report.h). The relative weight νβ is 1 for RLS on every sample (β = 1/ν), and
// for the Kárný–Hangos Student-t family with k degrees of freedom it tends to
//   νβ → (k+1)/(k + ê²/D_y)                                       [spec cauchy-estimator.md §6, large ν]
// so νβ < w flags |ê| > √((k+1)/w − k)·√D_y: for w = 0.2 that is 3√D_y for Cauchy (k = 1) and
// √17·√D_y for Student-t k = 3. A 20σ outlier gets νβ ≈ 0.005 (Cauchy). RLS never flags.
//
// Example:
//   ident::OutlierDecision decide;                         // threshold 0.2
//   if (decide.Flags(est.Update(y, z))) { /* clean y before it enters later regressors */ }
#pragma once

#include <cmath>
#include <string>

#include <fmt/format.h>

#include "common/step_report.h"

namespace ident {

struct OutlierDecision {
  double max_relative_weight = 0.2;  // w: flag an updated sample with ν(t)β(t) < w

  bool Flags(const StepReport& report) const {
    return report.updated() && report.nu * report.weight < max_relative_weight;  // NaN never flags
  }
  // "" if valid, else one line naming the option.
  std::string Validate() const {
    if (!(std::isfinite(max_relative_weight) && max_relative_weight >= 0 && max_relative_weight < 1))
      return fmt::format("outlier weight threshold = {}; need 0 <= threshold < 1", max_relative_weight);
    return "";
  }
};

}  // namespace ident
