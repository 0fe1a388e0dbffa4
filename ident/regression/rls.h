// Recursive least squares on the LD-factorised extended information matrix (normalised RLS).
//
//   Model:  y(t) = Θ'z(t) + e(t),  e Gaussian.
//   Step:   ν(t) = λν(t−1) + 1,  β(t) = 1/ν(t),  V(t) = (1−β)Ṽ + β h h',  h = [y; z]   [spec §7c, eq. (55)]
//           (the unnormalised information ν(t)V(t) = λ ν(t−1)V(t−1) + h h'); stabilised forgetting
//           as in spec §7b.
//   Read-outs: Θ̂ = V_z⁻¹V_zy; residual sum ν D_y; noise variance s² = ν D_y/(n − ρ) with
//           n = Σ λ^k the (discounted) sample count; Cov(Θ̂) = s² (ν V_z)⁻¹ = D_y V_z⁻¹/(n − ρ).
//
// Cost per Update() (m = ρ+1; one flop = one add, multiply, divide or square root; counted from the
// loops in ident/regression/internal/step_driver.h, step_guard.h, extended_information.h and ld_factor.h):
//   input check |h|² = y² + |z|², |h|               2ρ + 2
//   ν̃ = λν, ν = ν̃ + 1, β = 1/ν, n ← λn + 1          5
//   one sweep (β = 1/ν is known first; ld_factor.h PlanFused):
//     back substitution L'g = h, ê = g_0             m(m−1)          [spec §6]
//     plan: new d, b_j (prefix-sum form), Σd, Σ|g|   12m + 2
//     rank-one update of L (Agee–Turner), in place   m(m−1)          [spec §6] (old rows kept: m(m−1)/2 stores)
//   guard verdict (bound on max|L|, Θ̂), commit      5 + 5           (step_guard.h; no copy; a refused
//                                                                     step puts the kept rows back)
//   total, exponential forgetting                    2m² + 10m + 2ρ + 19 = 2ρ² + 16ρ + 31
//                                                    (ρ = 4: 127 flops, plus ≈ 4m comparisons)
//   stabilised forgetting adds a copy of L, d and m  ≈ (2/3)m³ + 4m²   (O(ρ³); ρ = 4: ≈ 190 more)
//   sparse rank-one updates with the rows of L_a [spec §7b]
//   a step the O(m) guard cannot prove healthy       + a copy of L, d and Σ|L| (O(m²); rare: extreme scales)
//   parameters() after an update (cached)            ρ²     (forward substitution)
//   CovarianceInto()                                 ≈ (5/6)ρ³ + O(ρ²)
// No step allocates after construction (fixed-size and dynamic variants alike).
//
// Real-time loop features (what MATLAB's recursive estimators offer; all allocation-free; Update, Skip,
// Reset and set_enabled are noexcept, set_forgetting and CovarianceInto throw only on invalid arguments):
//   set_enabled(false)      Update() returns kSkipped and leaves the state bit-identical (EnableAdapt)
//   Skip()                  a missing sample: kSkipped, state untouched
//   Reset()                 back to the prior (ν0, V0)
//   set_forgetting(λ)       takes effect at the next update (throws only for λ ∉ (0, 1])
//   CovarianceInto(P)       Cov(Θ̂) into a caller-owned ρ x ρ matrix, at any time
//
// Example:
//   ident::BasicRecursiveLeastSquares<4> rls(/*num_parameters=*/4, {.forgetting = {.factor = 0.99}});
//   Eigen::Matrix4d P;
//   for (...) {
//     rls.set_enabled(excitation_ok);
//     ident::StepReport r = sensor_ok ? rls.Update(y, z) : rls.Skip();
//     rls.CovarianceInto(P);
//   }
//   Eigen::Vector4d theta = rls.parameters();
#pragma once

#include <Eigen/Core>

#include "ident/regression/weighted_regression.h"

namespace ident {

// Recursive least squares is the LD-form shell with the least-squares weight.
template <int Rho = Eigen::Dynamic>
using BasicRecursiveLeastSquares = BasicWeightedRegression<LeastSquaresWeight, Rho>;

using RecursiveLeastSquares = BasicRecursiveLeastSquares<Eigen::Dynamic>;

}  // namespace ident
