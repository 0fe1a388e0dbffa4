// What both paths of the MAP smoother share around the interior-point iteration (internal to
// ident/smoothing/; see ident/smoothing/map_smoother.h): the unit they iterate in, and the result assembled
// from the final iterate.
#pragma once

#include <algorithm>
#include <vector>

#include <Eigen/Core>

#include "ident/smoothing/map_smoother.h"

namespace ident::internal {

class ForkJoin;  // ident/smoothing/internal/fork_join.h

// The KKT residual both paths stop on: the largest of the complementarity per constraint mu (in the unit
// σ), the total complementarity relative to the objective's size (1e-12 per constraint standing in for an
// objective of zero), and the relative R3, R4.
inline double RelativeKktResidual(double total_complementarity, double objective_scale, double num_constraints,
                                  double relative_r3, double relative_r4) {
  if (!(num_constraints > 0)) return std::max(relative_r3, relative_r4);
  const double mu = total_complementarity / num_constraints;
  const double relative = total_complementarity / std::max(objective_scale, 1e-12 * num_constraints);
  return std::max({mu, relative, relative_r3, relative_r4});
}

// The stall test of both paths: the KKT residual fell by less than kStallProgress over kStallWindow iterations.
inline constexpr int kStallWindow = 10;
inline constexpr double kStallProgress = 0.9;
// The stopping rule of both paths before a Newton step, but for diverging multipliers: converged (kkt at the
// tolerance), out of iterations, or stalled (`history` holds each iteration's kkt; `relative_floor` is the
// residuals' round-off floor relative to the dual values and `state_size` the states' size, for the
// message). Sets res's status and message; returns true if the iteration stops.
bool StopsOnProgress(const MapSmootherOptions& options, int iteration, double kkt, const std::vector<double>& history,
                     double relative_floor, double state_size, MapSmootherResult* res);
// The status and message of multipliers that diverge: |u| = `u` (in the data's unit) at time t, `ratio` times
// the penalties' bounds and the data.
void MarkDiverging(double u, int t, double ratio, MapSmootherResult* res);

// The stationarity residual's round-off floor in units of eps × the magnitudes it is computed from.
inline constexpr double kFloorFactor = 64;
// The same for the residuals r = z - Hx of R3, relative to the states' size: tighter, since the gap of a
// penalty with a kink grows with |r| at its kinks.
inline constexpr double kResidualFloorFactor = 1;

// The unit in which both paths iterate: the median of |z_{t+1} - z_t| over all measurement coordinates
// (the typical step of the data, which neither the magnitude of the states nor a shift of the origin
// changes), else the mean, else max |z|; with all measurements zero, the largest finite bound, offset b
// or linear term p of the penalties' PLQ forms; else 1. Each path solves the problem in this unit — z/σ and
// every PLQ form with p, b, lo, hi divided by σ (the penalty σ⁻²ρ(σr), so that (P) at x/σ is σ⁻² times
// (P) at x [BCW eq. (2.1)]) — and multiplies the states and dual controls back. The iterates, and so the
// absolute stopping tests, are then the same for data in any unit.
double MapSmootherDataUnit(const MapSmootherProblem& problem);

// What the dual polish of the certificate needs from the last iterate besides res->u, in the data's unit:
// the process terms' dual values v_t = p + B'u (in d f_t(w_t) at the optimum) and the Newton weights
// W = B'K^-1 B of every term (the derivative of a term's dual value with respect to its residual).
struct MapSmootherDualIterate {
  Eigen::MatrixXd process_dual;        // n x (T+1)
  Eigen::MatrixXd process_weight;      // n*n x (T+1), column t = W of f_t (column-major n x n); or one per
                                       // penalty of {f} or {f_0, f} (ProcessWeightColumn)
  Eigen::MatrixXd measurement_weight;  // nz*nz x (T+1), column t = W of g_t
};

// The column of MapSmootherDualIterate::process_weight that holds W of f_t: t, or with one or two columns
// (one per penalty of {f} or {f_0, f}, as MapSmootherProblem::process) that of f_t.
inline int ProcessWeightColumn(const Eigen::MatrixXd& process_weight, int t) {
  return process_weight.cols() == 1 ? 0 : process_weight.cols() == 2 ? (t == 0 ? 0 : 1) : t;
}

// From res->x (states) and res->u (dual controls p + B'u of each measurement term, before projection),
// both in the data's unit, computes w, the dual point, both objectives, the certified gap, x_from_dual and
// the non-unique reconstruction steps, then the status's final word and res->message.
//  - Dual polish (when `dual` is given): the measurement and process dual values of the iterate satisfy the
//    dual constraint A'y = H'u only up to the stationarity residual R4, and y(u) from the backward recursion
//    amplifies that residual by the powers of F' (T^2 for a double integrator). Two projections onto the
//    constraint in the Newton metric, N xi = -rho with N = sum J'WJ (the Newton matrix), v += W_f A xi,
//    u -= W_g H xi, bring rho to round-off of the dual values, independent of the states' magnitude. It runs
//    only when the iterate's own dual point certifies a relative gap above options.tolerance or
//    options.gap_tolerance; the tighter of the two certificates is kept.
//  - Certificate: u projected into dom g*, y = y(u) by the recursion in double-double, and the gap as the
//    compensated sum of the per-term Fenchel-Young gaps (each >= 0 in exact arithmetic), which equals
//    P(x) - D(u) exactly when y is y(u); w = Ax and r = z - Hx by compensated dot products.
// z_scale: the measurements' scale in the data's unit (domain tolerances); mu: the final complementarity in
// the iteration's unit (how far the dual is located). `fork`: if given (and it has a worker), independent parts
// run on two threads, with the same results.
void FinishMapSmootherResult(const MapSmootherProblem& problem, const MapSmootherOptions& options, double z_scale,
                             double mu, const MapSmootherDualIterate* dual, MapSmootherResult* res,
                             ForkJoin* fork = nullptr);

}  // namespace ident::internal
