// Per-step health check and rollback shared by the LD-form regression estimators (RLS, Student-t);
// ident/regression/internal/step_driver.h runs it.
//
// A step is healthy if ν > 0 is finite, every d_i is finite and ≥ d_min (DBL_MIN: a positive normal
// number), and L and Θ̂ = L_z⁻¹l_zy are finite. An unhealthy step is undone (the caller reports
// StepStatus::kNumericalFailure), so it never leaves a non-finite or degenerate state behind.
//
// Fast path — decided before the state is touched, O(ρ), nothing copied:
//   d   the plan of the update (ExtendedInformation::PlanApply) gives the new d exactly (the
//       commit writes these very numbers), so "d_i ≥ d_min and finite" is checked on the plan;
//   L   with M ≥ max|L_ij| (kept by the factor, see LdFactor::OffDiagonalBound), the new L is bounded
//       by M' = M + max|b_j|(|h| + Σ|g_j| M) (back substitution, LdFactor::CommitUpdate);
//   Θ̂   forward substitution gives |Θ̂|_1 ≤ (1 + M')^ρ − 1, so M' < (2^(1000/ρ) − 1)/2 proves Θ̂
//       (and L) finite, 2^1000 < DBL_MAX. If M' fails with the grown bound, M is recomputed exactly
//       once (O(ρ²)) and the test repeated.
// Slow path — only when the fast path cannot prove the step healthy: Save() the factor (O(ρ²) copy),
// commit, Healthy() on the result (Σ|L| bound, else entry by entry), Restore() if it failed.
// Allocation-free after construction.
//
// Example (what StepDriver does):
//   ident::StepGuard<> guard(stats_);             // in the constructor, after stats_
//   auto plan = stats_.PlanApply(beta);
//   switch (guard.Judge(stats_, plan, nu, |h|)) {
//     case Verdict::kHealthy: stats_.CommitApply(nu, |h|); break;
//     case Verdict::kUnhealthy: stats_.RestoreNu(nu_before); break;      // reject
//     case Verdict::kUnknown: guard.Save(stats_); stats_.CommitApply(nu, |h|);
//                             if (!guard.Healthy(stats_)) guard.Restore(stats_, nu_before);
//   }
#pragma once

#include <cmath>
#include <limits>

#include "ident/linalg/ld_factor.h"
#include "ident/regression/internal/extended_information.h"

namespace ident {

template <int Dim = Eigen::Dynamic>
class StepGuard {
 public:
  static constexpr double kNormalMin = std::numeric_limits<double>::min();

  explicit StepGuard(const ExtendedInformation<Dim>& stats)
      : backup_(stats.factor()), theta_bound_(std::exp2(1000.0 / stats.num_parameters()) - 1) {}

  enum class Verdict {
    kHealthy,    // committing the plan provably leaves a healthy state
    kUnhealthy,  // it certainly does not (ν or the new d fail): do not commit
    kUnknown,    // d and ν pass, L/Θ̂ could not be bounded: commit on a copy and check (slow path)
  };

  // The verdict on committing `plan` (made by stats.PlanApply after Prepare) with ν(t) = nu, every
  // d_i to be ≥ d_min; h_bound ≥ max|h_i|. O(ρ) (O(ρ²) when the bound on L has to be recomputed).
  Verdict Judge(const ExtendedInformation<Dim>& stats, const typename LdFactor<Dim>::Plan& plan, double nu,
                double h_bound, double d_min = kNormalMin) const {
    if (!(std::isfinite(nu) && nu > 0 && std::isfinite(plan.d_sum) && plan.min_d >= d_min))
      return Verdict::kUnhealthy;  // the plan's d are exactly the d the commit would write
    const auto& f = stats.factor();
    const double limit = theta_bound_ / 2;
    if (f.GrownBound(f.OffDiagonalBound(), h_bound) < limit) return Verdict::kHealthy;  // not NaN
    if (f.GrownBound(f.TightenOffDiagonalBound(), h_bound) < limit) return Verdict::kHealthy;
    return Verdict::kUnknown;
  }

  void Save(const ExtendedInformation<Dim>& stats) { backup_ = stats.factor(); }
  // Back to the saved factor with ν = nu.
  void Restore(ExtendedInformation<Dim>& stats, double nu) const { stats.Reset(nu, backup_); }

  // The full check on a state (the slow path's verdict after a committed step).
  bool Healthy(const ExtendedInformation<Dim>& stats, double d_min = kNormalMin) const {
    const auto& f = stats.factor();
    if (!(std::isfinite(stats.nu()) && stats.nu() > 0 && f.d().allFinite() && f.d().minCoeff() >= d_min)) return false;
    const double S = f.L().cwiseAbs().sum();
    if (S < theta_bound_) return true;  // false for S = NaN or Inf too
    return f.L().allFinite() && stats.parameters().allFinite();
  }

 private:
  LdFactor<Dim> backup_;
  double theta_bound_;  // 2^(1000/ρ) − 1
};

}  // namespace ident
