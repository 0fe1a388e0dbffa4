// The MAP smoother's fused fast path (internal to ident/smoothing/map_smoother.cc; see ident/smoothing/map_smoother.h).
//
// For the common structure — every process penalty f_t without finite bounds (quadratic), every
// measurement scalar (nz = 1) with an identity-B PLQ penalty with both bounds finite (l1, Huber,
// quantile, scalar box monitoring) — the interior-point iteration of SolveMapSmoother (Aravkin, Burke &
// Pillonetto, JMLR 14 (2013), sec. 4; Mehrotra predictor-corrector) runs as five fused passes over time
// per iteration, with no per-term dispatch:
//   1. the pending step, the residuals R3, R4 and the complementarity of the iterate;
//   2. the block LDL' factorisation of the Newton matrix fused with the forward substitution of the
//      predictor right-hand side, from both ends of the record at once (a twisted factorisation): from the start,
//      P_t = S_t^-1 with S_t = Db_t - E_t P_{t-1} E_t' + K_t^-1 H_t'H_t; from the end, the same with
//      E_{t+1}' Q_{t+1} E_{t+1}; at the middle step m = T/2 both. The measurement's rank-one term enters with the
//      factor K_t (n = 2: the adjugate in closed form, one division per block; else Sherman-Morrison; no square
//      roots, no cancellation when K_t^-1 ~ 1/mu at a kink); P_t stored;
//   3. the substitution outwards from m, dx_t = v_t - P_t E_{t+1}' dx_{t+1} above and dx_t = w_t - Q_t E_t dx_{t-1}
//      below, fused with the recovery of du, ds, dq, the step length and the three sums that give the
//      complementarity after the affine step;
//   4., 5. the same forward/backward passes for the corrector.
// Each pass runs over its two halves on two threads (MapSmootherOptions::threads; ident/smoothing/internal/
// fork_join.h), or one after the other: the same operations either way, so the same results.
// Same start, same directions (in exact arithmetic), same stopping rule as the general path.
//
// Example (what SolveMapSmoother does):
//   if (options.fast_path && internal::MapSmootherFastPathApplies(problem))
//     return internal::SolveMapSmootherFastPath(problem, options);
#pragma once

#include "ident/smoothing/map_smoother.h"

namespace ident::internal {

// True if the fast path handles the problem (structure above, state dimension 1..4).
bool MapSmootherFastPathApplies(const MapSmootherProblem& problem);

// The interior point on the fast path, then the common finish (objectives, dual point, reconstruction).
MapSmootherResult SolveMapSmootherFastPath(const MapSmootherProblem& problem, const MapSmootherOptions& options);

}  // namespace ident::internal
