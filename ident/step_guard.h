// Per-step health check and rollback shared by the LD-form regression estimators (RLS, Student-t).
//
// A step is healthy if ν > 0 is finite, every d_i is finite and ≥ d_min (DBL_MIN: a positive normal
// number), and L and Θ̂ = L_z⁻¹l_zy are finite. The estimator saves its statistics before a step and
// restores them if the step was not healthy (reporting StepStatus::kNumericalFailure), so a bad step
// never leaves a non-finite or degenerate state behind. O(ρ²), allocation-free after construction.
//
// Fast path, one vectorised pass: S = Σ|L_ij| is finite iff L is (barring overflow of the sum), and
// forward substitution gives |Θ̂|_1 ≤ (1 + max|L_ij|)^ρ − 1 ≤ (1 + S)^ρ, so S < 2^(1000/ρ) − 1
// guarantees a finite Θ̂ (2^1000 < DBL_MAX) without solving; otherwise L and Θ̂ are checked entry by entry.
//
// Example:
//   ident::StepGuard<> guard(stats_);            // in the constructor, after stats_
//   guard.Save(stats_);  ...step...
//   if (!guard.Healthy(stats_)) { guard.Restore(stats_); return {StepStatus::kNumericalFailure}; }
#pragma once

#include <cmath>
#include <limits>

#include "ident/extended_information.h"

namespace ident {

template <int Dim = Eigen::Dynamic>
class StepGuard {
 public:
  explicit StepGuard(const ExtendedInformation<Dim>& stats)
      : backup_(stats), theta_bound_(std::exp2(1000.0 / stats.num_parameters()) - 1) {}

  void Save(const ExtendedInformation<Dim>& stats) { backup_ = stats; }
  void Restore(ExtendedInformation<Dim>& stats) const { stats = backup_; }

  bool Healthy(const ExtendedInformation<Dim>& stats, double d_min = std::numeric_limits<double>::min()) const {
    const auto& f = stats.factor();
    if (!(std::isfinite(stats.nu()) && stats.nu() > 0 && f.d().allFinite() && f.d().minCoeff() >= d_min))
      return false;
    const double S = f.L().cwiseAbs().sum();
    if (S < theta_bound_) return true;  // false for S = NaN or Inf too
    return f.L().allFinite() && stats.parameters().allFinite();
  }

 private:
  ExtendedInformation<Dim> backup_;
  double theta_bound_;  // 2^(1000/ρ) − 1
};

}  // namespace ident
