// The one guarded step shared by the LD-form regression estimators (RLS, Student-t/Cauchy):
// validate the sample, forget, innovation, the estimator's weight β, plan, check, commit or roll back.
//
//   1. reject (state untouched) a sample with a non-finite entry, a regressor of the wrong size, or
//      y² + |z|² overflowing: kRejectedInvalid;
//   2. forgetting with λ (exponential or stabilised) [spec §7b]; ν(t) = ν̃ + 1;
//   3. ξ, ξ_z, ê by one back substitution (ExtendedInformation::Prepare) [spec §6];
//   4. β = weight(ν(t), innovation) — 1/ν for RLS, the weighting-cubic root for Kárný–Hangos; a
//      β ∉ (0, 1) (NaN: refused) undoes the step: kNumericalFailure;
//   5. V(t) = (1−β)Ṽ + βhh', guarded by ident/regression/internal/step_guard.h: proven healthy in O(ρ) before the state
//      is touched (the common case: no copy), otherwise copied, committed, checked and restored if
//      unhealthy (kNumericalFailure, state bit-identical to before the call);
//   windup: with λ < 1 and windup_floor > 0, a step that would leave some d_i below windup_floor (or
//      fail the check) is retaken once with λ = 1 — d then shrinks only as ν/(ν+1), so exponential
//      forgetting without excitation neither underflows nor freezes the estimator.
// Costs nothing beyond the estimator's own arithmetic except O(ρ) checks in the common case.
// Allocation-free, noexcept.
//
// Example (inside an estimator holding `ExtendedInformation<kDim> stats_` and `StepDriver<kDim> driver_{stats_}`):
//   const DrivenStep s = driver_.template Run</*WithXi=*/false>(stats_, {lambda, stabilised, 0x1p-900}, prior_nu0,
//                                    prior_factor_, y, z, [](double nu, const Innovation&) { return 1 / nu; });
//   if (s.report.updated()) samples_ = s.lambda * samples_ + 1;
#pragma once

#include <cmath>
#include <limits>

#include <Eigen/Core>

#include "common/step_report.h"
#include "ident/linalg/ld_factor.h"
#include "ident/regression/internal/extended_information.h"
#include "ident/regression/internal/step_guard.h"

namespace ident {

// How one step forgets.
struct StepSettings {
  double lambda = 1.0;        // forgetting factor λ ∈ (0, 1]
  bool stabilised = false;    // stabilised forgetting towards (ν_a, V_a) [spec §7b]
  double windup_floor = 0.0;  // > 0: the windup retry above (only with λ < 1)
};

struct DrivenStep {
  StepReport report;
  double lambda = 1.0;  // the λ the step was taken with (λ, or 1 after a windup retry)
};

template <int Dim = Eigen::Dynamic>
class StepDriver {
 public:
  explicit StepDriver(const ExtendedInformation<Dim>& stats) : guard_(stats) {}

  // One guarded step (see the header comment). `weight(double nu, const Innovation&)` returns β;
  // it is called once per attempt and may record details of the step. (ν_a, V_a): the stabilised
  // forgetting's target (the prior), unused otherwise.
  // WithXi = false: the weight needs only ν (RLS); ξ, ξ_z are then NaN and not computed.
  // BetaFirst = true: the weight reads only ν (its Innovation argument is all NaN), so β is taken first and
  // the innovation, plan and new L come from one sweep (ExtendedInformation::PrepareAndPlan); the same
  // numbers and reports as BetaFirst = false.
  template <bool WithXi = true, bool BetaFirst = false, class Derived, class Weight>
  DrivenStep Run(ExtendedInformation<Dim>& stats, const StepSettings& s, double nu_a, const LdFactor<Dim>& Va, double y,
                 const Eigen::MatrixBase<Derived>& z, Weight&& weight) noexcept {
    // The report is carried field by field and built once, by the one return below: a report assembled in
    // memory on one path and copied whole on another is reloaded wider than it was stored, which stalls
    // until the step retires.
    constexpr double nan = std::numeric_limits<double>::quiet_NaN();
    StepStatus status = StepStatus::kRejectedInvalid;
    double beta = nan, nu = nan, e = nan, lambda = s.lambda;
    // |h|² = y² + |z|² is finite iff every entry is and nothing overflows (squares cannot cancel).
    const double h_norm2 = y * y + z.squaredNorm();
    if (z.size() == stats.num_parameters() && std::isfinite(h_norm2)) [[likely]] {
      const Sample<Derived> sample{y, z, std::sqrt(h_norm2)};
      const bool windup = s.lambda < 1 && s.windup_floor > 0;
      const Outcome o =
          Attempt<WithXi, BetaFirst>(stats, s.stabilised, s.lambda,
                                     windup ? s.windup_floor : StepGuard<Dim>::kNormalMin, nu_a, Va, sample, weight);
      status = o.report.status, beta = o.report.weight, nu = o.report.nu, e = o.report.prediction_error;
      if (windup && o.unhealthy) [[unlikely]] {
        const StepReport r = Retry<WithXi, BetaFirst>(stats, s.stabilised, nu_a, Va, sample, weight);
        status = r.status, beta = r.weight, nu = r.nu, e = r.prediction_error, lambda = 1.0;
      }
    }
    return {{status, beta, nu, e}, lambda};
  }

 private:
  template <class Derived>
  struct Sample {
    double y;
    const Eigen::MatrixBase<Derived>& z;
    double h_norm;  // |h| ≥ max|h_i|
  };
  struct Outcome {
    StepReport report;
    bool unhealthy = false;  // failed the health check (not: β refused)
  };

  // The windup retry with λ = 1 (rare: out of line, so that the common path's Attempt is inlined).
  template <bool WithXi, bool BetaFirst, class Derived, class Weight>
  [[gnu::noinline]] StepReport Retry(ExtendedInformation<Dim>& stats, bool stabilised, double nu_a,
                                     const LdFactor<Dim>& Va, const Sample<Derived>& x, Weight& weight) noexcept {
    return Attempt<WithXi, BetaFirst>(stats, stabilised, 1.0, StepGuard<Dim>::kNormalMin, nu_a, Va, x, weight).report;
  }

  // Inlined into the estimator's Update(): an out-of-line call returns the report through memory, whose
  // reload after the call waits for the whole step (the narrow stores cannot be forwarded to a wide load).
  template <bool WithXi, bool BetaFirst, class Derived, class Weight>
  [[gnu::always_inline]] inline Outcome Attempt(ExtendedInformation<Dim>& stats, bool stabilised, double lambda,
                                                double d_min, double nu_a, const LdFactor<Dim>& Va,
                                                const Sample<Derived>& x, Weight& weight) noexcept {
    const double nu_before = stats.nu();
    if (stabilised) {
      guard_.Save(stats);  // stabilised forgetting changes the factor itself
      stats.ForgetStabilised(lambda, nu_a, Va);
    } else {
      stats.ForgetExponential(lambda);  // ν only
    }
    const double nu = stats.nu() + 1;
    if constexpr (BetaFirst) {
      constexpr double nan = std::numeric_limits<double>::quiet_NaN();
      const double beta = weight(nu, Innovation{nan, nan, nan});
      if (!(beta > 0 && beta < 1)) {
        const double e = stats.template Prepare<false>(x.y, x.z).prediction_error;
        Undo(stats, stabilised, nu_before);
        return {{StepStatus::kNumericalFailure, beta, nu, e}};
      }
      double e;
      const auto& plan = stats.PrepareAndPlan(x.y, x.z, beta, e);
      // L and d are already the new ones (the old ones kept): a refused step rolls them back.
      bool healthy = true;
      switch (guard_.Judge(stats, plan, nu, x.h_norm, d_min)) {
        case StepGuard<Dim>::Verdict::kHealthy:
          stats.CommitFused(nu, x.h_norm);
          break;
        case StepGuard<Dim>::Verdict::kUnknown:
          stats.CommitFused(nu, x.h_norm);
          healthy = guard_.Healthy(stats, d_min);
          break;
        case StepGuard<Dim>::Verdict::kUnhealthy:
          healthy = false;
          break;
      }
      if (!healthy) {
        if (stabilised)
          guard_.Restore(stats, nu_before);
        else
          stats.RollbackFused(nu_before);
      }
      return {{healthy ? StepStatus::kUpdated : StepStatus::kNumericalFailure, beta, nu, e}, !healthy};
    }
    const Innovation in = stats.template Prepare<WithXi>(x.y, x.z);
    const double beta = weight(nu, in);
    Outcome o{{StepStatus::kUpdated, beta, nu, in.prediction_error}};
    if (!(beta > 0 && beta < 1)) {
      Undo(stats, stabilised, nu_before);
      o.report.status = StepStatus::kNumericalFailure;
      return o;
    }
    const auto& plan = stats.template PlanApply<WithXi>(beta);
    switch (guard_.Judge(stats, plan, nu, x.h_norm, d_min)) {
      case StepGuard<Dim>::Verdict::kHealthy:
        stats.CommitApply(nu, x.h_norm);
        return o;
      case StepGuard<Dim>::Verdict::kUnknown:
        if (!stabilised) guard_.Save(stats);  // the factor is still the one before the step
        stats.CommitApply(nu, x.h_norm);
        if (guard_.Healthy(stats, d_min)) return o;
        guard_.Restore(stats, nu_before);
        break;
      case StepGuard<Dim>::Verdict::kUnhealthy:
        Undo(stats, stabilised, nu_before);
        break;
    }
    o.report.status = StepStatus::kNumericalFailure;
    o.unhealthy = true;
    return o;
  }

  void Undo(ExtendedInformation<Dim>& stats, bool stabilised, double nu_before) {
    if (stabilised)
      guard_.Restore(stats, nu_before);
    else
      stats.RestoreNu(nu_before);
  }

  StepGuard<Dim> guard_;
};

}  // namespace ident
