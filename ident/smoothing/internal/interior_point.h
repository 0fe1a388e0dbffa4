// The general path of the MAP smoother (internal to ident/smoothing/; see ident/smoothing/map_smoother.h):
// the primal-dual interior-point method of Aravkin, Burke & Pillonetto, JMLR 14 (2013) [ABP], sec. 4, with
// Mehrotra's predictor-corrector, on any problem SolveMapSmoother accepts.
#pragma once

#include "ident/smoothing/map_smoother.h"

namespace ident::internal {

// The problem and options are valid (SolveMapSmoother checks them).
MapSmootherResult SolveMapSmootherInteriorPoint(const MapSmootherProblem& problem, const MapSmootherOptions& options);

}  // namespace ident::internal
