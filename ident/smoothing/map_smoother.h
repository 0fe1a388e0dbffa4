// MAP smoothing of a linear system with log-concave (convex-penalty) noise, and its dual control
// problem (Bassett, Casey & Wets, "Log-Concave Duality in Estimation and Control" [BCW]).
//
//   (P)  min_x  sum_{t=0..T} f_t(w_t) + sum_{t=0..T} g_t(z_t - H_t x_t)                 [BCW Prop. 2.1]
//        s.t.   x_{t+1} = F_t x_t + w_{t+1} (t = 0..T-1),   x_0 = w_0
//
//   (D)  max_u  sum_{t=0..T} z_t'u_t - g_t*(u_t) - f_t*(y_t)                             [BCW Thm 2.4, eq. (6)]
//        s.t.   y_t = F_t' y_{t+1} + H_t' u_t (t = 0..T-1),   y_T = H_T' u_T
//
// Signs: the Lagrangian of Thm 2.3, L = f(w) + z'u - g*(u) - u'Hx + y'(Ax - w), gives
// inf_{w,x} L = z'u - g*(u) - f*(y) on A'y = H'u (Thm 2.4 proof). The objectives printed in Thm 2.5
// and Cor. 2.9 carry the opposite overall sign; with the signs above, weak duality reads
// dual(u) <= primal(x) for every feasible x and every u (tested). For monitoring functions
// f_t* = 1/2 y'M_t y on W_t and g_t* = 1/2 u'N_t u on V_t (Lemma 2.8).
// At a saddle point y_t in d f_t(w_t), u_t in d g_t(z_t - H_t x_t), and w_t in d f_t*(y_t), which
// reconstructs the primal states from the dual (w* = y* for f = 1/2|w|^2, [BCW] sec. 3).
//
// Solver: the primal-dual interior-point method of Aravkin, Burke & Pillonetto [ABP] (JMLR 14 (2013),
// sec. 4) for PLQ penalties rho(r) = p'r + p0 + sup_{lo<=v<=hi} { v'(B r - b) - 1/2 v'M v }, with a
// Mehrotra predictor-corrector. Eliminating slacks and multipliers per term leaves the x-system
//   sum_terms J' B' K^-1 B J dx = rhs,   K = M + diag(q_hi/s_hi + q_lo/s_lo),
// which is block tridiagonal in time (J couples x_{t-1}, x_t only): O(T n^3) per iteration.
//
// Example:
//   ident::MapSmootherProblem p;
//   p.F = {F}; p.H = {H}; p.z = z;                              // z: nz x (T+1)
//   p.process = {Penalty::Quadratic(P0), Penalty::Quadratic(Q)};  // f_0, then f_1..f_T
//   p.measurement = {Penalty::L1()};
//   ident::MapSmootherResult r = ident::SolveMapSmoother(p);
//   // r.x (n x (T+1)), r.primal, r.dual, r.gap, r.max_abs_x_difference
#pragma once

#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "models/penalties.h"

namespace ident {

struct MapSmootherProblem {
  // Dynamics F_t (n x n): one matrix (time-invariant) or T matrices (F[t] maps x_t to x_{t+1}).
  std::vector<Eigen::MatrixXd> F;
  // Measurement matrices H_t (nz x n): one matrix or T+1.
  std::vector<Eigen::MatrixXd> H;
  // Measurements, nz x (T+1): column t is z_t. Its column count defines T.
  Eigen::MatrixXd z;
  // Process penalties f_t on w_t: {f} (all t), {f_0, f} (f_0 on w_0 = x_0, f on w_1..w_T), or T+1.
  std::vector<models::Penalty> process;
  // Measurement penalties g_t on z_t - H_t x_t: one (all t) or T+1.
  std::vector<models::Penalty> measurement;

  int T() const { return static_cast<int>(z.cols()) - 1; }
  int state_dim() const { return H.empty() ? 0 : static_cast<int>(H[0].cols()); }
  int measurement_dim() const { return static_cast<int>(z.rows()); }
  const Eigen::MatrixXd& Ft(int t) const { return F.size() == 1 ? F[0] : F[t]; }
  const Eigen::MatrixXd& Ht(int t) const { return H.size() == 1 ? H[0] : H[t]; }
  const models::Penalty& ft(int t) const;
  const models::Penalty& gt(int t) const { return measurement.size() == 1 ? measurement[0] : measurement[t]; }
};

// Throws InvalidArgument naming the field for missing/mis-sized matrices, penalties of the wrong
// dimension or non-finite data.
void ValidateMapSmootherProblem(const MapSmootherProblem& problem);

struct MapSmootherOptions {
  int max_iterations = 100;  // interior-point (Newton) iterations
  // On the complementarity and the KKT residuals, each relative to the magnitudes it is computed from;
  // a residual at its round-off floor (set by the size of the states) counts as met.
  double tolerance = 1e-10;
  // A converged iterate whose certified relative duality gap (relative_gap_bound) exceeds this is reported
  // as kStalled: the KKT conditions hold to rounding, but the certificate shows an accuracy of only that gap.
  double gap_tolerance = 1e-6;
  double step_fraction = 0.995;  // fraction-to-boundary factor for s, q > 0
  // Use the fused fast path (ident/smoothing/internal/map_smoother_fast_path.h) when the problem has its structure:
  // bound-free (quadratic) process penalties, scalar measurements with l1 / Huber / quantile / scalar box penalties,
  // n <= 4. Same iteration and result up to rounding; false forces the general path (tests compare both).
  bool fast_path = true;
  // Threads of the fast path: 1 (the calling thread), 2 or more (a second thread), 0 (a second thread from
  // T = 1023 on). Its factorisation runs from both ends of the record at once; the results are the same for every
  // value.
  int threads = 0;
  // If set: called at every iteration (0, 1, …, the final one) with its relative KKT residual, the stopping
  // test's (compared with `tolerance`; MapSmootherResult::kkt_residual is the final call's), e.g. for progress.
  std::function<void(int iteration, double kkt_residual)> on_iteration;
  std::string Validate() const;  // "" if valid
};

enum class MapSmootherStatus {
  kConverged,         // KKT conditions met to `tolerance`, certified relative gap <= gap_tolerance
  kMaxIterations,     // iterate returned as is; objectives/gap still evaluated
  kInfeasible,        // multipliers diverged: (P) has no feasible point (e.g. residual outside a support)
  kNumericalFailure,  // the Newton matrix lost positive definiteness
  kStalled,           // no progress at a residual above `tolerance`, or a certified gap above gap_tolerance:
                      // the iterate, its objectives and its certified gap are returned (message says how far)
};
const char* ToString(MapSmootherStatus status);

struct MapSmootherResult {
  MapSmootherStatus status = MapSmootherStatus::kNumericalFailure;
  std::string message;
  int iterations = 0;
  // At the returned iterate: the largest of the complementarity per constraint, the total complementarity
  // over the objective's size, and |R3|, |R4| over their scales or round-off floors (the stopping test).
  double kkt_residual = 0;
  Eigen::MatrixXd x;        // n x (T+1) MAP states
  Eigen::MatrixXd w;        // n x (T+1) process noise w_t = x_t - F_{t-1} x_{t-1}, w_0 = x_0
  Eigen::MatrixXd u;        // nz x (T+1) dual controls of (D)
  Eigen::MatrixXd y;        // n x (T+1) dual states, from u by the dynamics of (D)
  double primal = 0;        // (P) at x
  double dual = 0;          // (D) at (u, y)
  double gap = 0;           // primal - dual (>= 0 up to rounding)
  double relative_gap = 0;  // gap / max(1, |primal|)
  // The duality certificate: the gap is summed as per-term Fenchel-Young gaps f(w)+f*(y)-y'w and
  // g(r)+g*(u)-u'r at the exactly dual-feasible (u, y(u)) (y in double-double), so that its round-off does
  // not grow with T; gap_error_bound bounds that round-off (a first-order running error bound).
  // primal - optimum <= gap + gap_error_bound. relative_gap_bound = (max(gap, 0) + gap_error_bound) /
  // max(1, |primal|); +inf when y(u) leaves dom f* (no finite certificate).
  double gap_error_bound = 0;
  double relative_gap_bound = 0;
  double dual_infeasibility = 0;    // max distance of u_t, y_t outside dom g_t*, dom f_t* before projection
  Eigen::MatrixXd x_from_dual;      // states rebuilt from y: w_t in d f_t*(y_t), then the dynamics
  double max_abs_x_difference = 0;  // max |x - x_from_dual|
  // w_t in d f_t*(y_t) determines w_t only where f_t* is differentiable at y_t. nonunique_steps lists the
  // t where it is not: y_t within tolerance of a kink of f_t* (a finite bound of the box dom f_t*, Vapnik's
  // y_i = 0, a slope of a piecewise-linear f_t), or the primal w_t differs from the element of d f_t*(y_t)
  // chosen by the reconstruction. x_from_dual equals x (to rounding) when the list is empty.
  std::vector<int> nonunique_steps;
  bool reconstruction_unique = true;  // nonunique_steps is empty
};

// (P) at x (n x (T+1)); +inf if infeasible. Residuals within `domain_tolerance` of a penalty's domain
// count as on its boundary.
double PrimalObjective(const MapSmootherProblem& problem, const Eigen::MatrixXd& x, double domain_tolerance = 0);
// y from u by the dynamics of (D): y_T = H_T'u_T, y_t = F_t'y_{t+1} + H_t'u_t.
Eigen::MatrixXd DualStates(const MapSmootherProblem& problem, const Eigen::MatrixXd& u);
// (D) at u (nz x (T+1)) with y = DualStates(u); -inf outside the conjugates' domains.
double DualObjective(const MapSmootherProblem& problem, const Eigen::MatrixXd& u);
// States from a dual solution: w_t = an element of d f_t*(y_t), x_0 = w_0, x_{t+1} = F_t x_t + w_{t+1}.
Eigen::MatrixXd StatesFromDual(const MapSmootherProblem& problem, const Eigen::MatrixXd& y);

MapSmootherResult SolveMapSmoother(const MapSmootherProblem& problem, const MapSmootherOptions& options = {});

}  // namespace ident
