// What both paths of the MAP smoother share around the interior-point iteration (internal to
// ident/smoothing/; see ident/smoothing/map_smoother.h): the unit they iterate in, and the result assembled
// from the final iterate.
#pragma once

#include <Eigen/Core>

#include "ident/smoothing/map_smoother.h"

namespace ident::internal {

// The unit in which both paths iterate: the median of |z_{t+1} - z_t| over all measurement coordinates
// (the typical step of the data, which neither the magnitude of the states nor a shift of the origin
// changes), else the mean, else max |z|; with all measurements zero, the largest finite bound, offset b
// or linear term p of the penalties' PLQ forms; else 1. Each path solves the problem in this unit — z/σ and
// every PLQ form with p, b, lo, hi divided by σ (the penalty σ⁻²ρ(σr), so that (P) at x/σ is σ⁻² times
// (P) at x [BCW eq. (2.1)]) — and multiplies the states and dual controls back. The iterates, and so the
// absolute stopping tests, are then the same for data in any unit.
double MapSmootherDataUnit(const MapSmootherProblem& problem);

// From res->x (states) and res->u (dual controls p + B'u of each measurement term, before projection),
// both in the data's unit, computes w, the projected dual point u, y, both objectives, the gap,
// x_from_dual and the non-unique reconstruction steps. z_scale: the measurements' scale in the data's unit
// (domain tolerances); mu: the final complementarity in the iteration's unit (how far the dual is located).
void FinishMapSmootherResult(const MapSmootherProblem& problem, double z_scale, double mu, MapSmootherResult* res);

// The iteration report shared by both paths: res->message from res->status and iterations.
void SetMapSmootherMessage(MapSmootherResult* res);

}  // namespace ident::internal
