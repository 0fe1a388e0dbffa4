#include "ident/smoothing/internal/map_smoother_result.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include "common/error.h"
#include "ident/linalg/internal/simd_clones.h"
#include "ident/smoothing/internal/compensated_arithmetic.h"
#include "ident/smoothing/internal/dual_polish.h"
#include "ident/smoothing/internal/fork_join.h"
#include "ident/smoothing/internal/small_kernels.h"

namespace ident::internal {
namespace {

using models::Penalty;

constexpr double kEps = std::numeric_limits<double>::epsilon();

// The primal residuals w_t = x_t - F_{t-1} x_{t-1} (into res->w) and r_t = z_t - H_t x_t (into *r) by
// compensated dot products: their round-off is relative to w and r, not to the (possibly far larger) states.
template <int kN>
IDENT_SIMD_CLONES void PrimalResiduals(const MapSmootherProblem& p, MapSmootherResult* res, Eigen::MatrixXd* r_out) {
  const int T = p.T(), n = kN > 0 ? kN : p.state_dim(), nz = p.measurement_dim();
  Eigen::MatrixXd& r = *r_out;
  res->w.resize(n, T + 1);
  r.resize(nz, T + 1);
  for (int t = 0; t <= T; ++t) {
    for (int i = 0; i < n; ++i) {
      DoubleDouble d;
      d.Add(res->x(i, t));
      if (t > 0)
        for (int j = 0; j < n; ++j) d.AddProduct(-p.Ft(t - 1)(i, j), res->x(j, t - 1));
      res->w(i, t) = d.value();
    }
    for (int i = 0; i < nz; ++i) {
      DoubleDouble d;
      d.Add(p.z(i, t));
      for (int j = 0; j < n; ++j) d.AddProduct(-p.Ht(t)(i, j), res->x(j, t));
      r(i, t) = d.value();
    }
  }
}

// Projects v (size entries) into the penalty's dom of the conjugate (rounding can leave it a hair outside a
// box); records the largest move in res->dual_infeasibility and returns it.
double ProjectIntoConjugateDomain(const Penalty& pen, double* v, int size, MapSmootherResult* res) {
  double violation = 0;
  for (int i = 0; i < size; ++i) {
    const double c = std::clamp(v[i], pen.conjugate_lo()(i), pen.conjugate_hi()(i));
    violation = std::max(violation, std::abs(c - v[i]));
    v[i] = c;
  }
  res->dual_infeasibility = std::max(res->dual_infeasibility, violation);
  return violation;
}

// y = y(u) by the dynamics of (D) in double-double (exact A'y = H'u up to O(eps^2)): res->y holds the
// leading parts, *y_lo_out the trailing ones. Returns the recursion's error bound on the gap.
template <int kN>
IDENT_SIMD_CLONES double DualStatesDoubleDouble(const MapSmootherProblem& p, MapSmootherResult* res,
                                                Eigen::MatrixXd* y_lo_out) {
  const int T = p.T(), n = kN > 0 ? kN : p.state_dim(), nz = p.measurement_dim();
  Eigen::MatrixXd& y_lo = *y_lo_out;
  res->y.resize(n, T + 1);
  y_lo.resize(n, T + 1);
  // The local residual of the double-double recursion is at most 4 (n + nz) eps^2 times the magnitudes
  // summed; its effect on the gap is sum |x_t| |rho_t| (EvaluateCertificate).
  double error_bound = 0;
  std::vector<DoubleDouble> next(n), cur(n);
  for (int t = T; t >= 0; --t) {  // y_T = H_T'u_T, y_t = F_t'y_{t+1} + H_t'u_t   [BCW Thm 2.5, A'y = H'u]
    for (int i = 0; i < n; ++i) {
      DoubleDouble d;
      double magnitude = 0;
      if (t < T)
        for (int k = 0; k < n; ++k) {
          d.AddProduct(p.Ft(t)(k, i), next[k]);
          magnitude += std::abs(p.Ft(t)(k, i) * next[k].hi);
        }
      for (int j = 0; j < nz; ++j) {
        d.AddProduct(p.Ht(t)(j, i), res->u(j, t));
        magnitude += std::abs(p.Ht(t)(j, i) * res->u(j, t));
      }
      d.Normalize();
      cur[i] = d;
      res->y(i, t) = d.hi;
      y_lo(i, t) = d.lo;
      error_bound += std::abs(res->x(i, t)) * 4 * (n + nz) * kEps * kEps * magnitude;
    }
    std::swap(next, cur);
  }
  return error_bound;
}

// y(u) farther outside dom f_t* than round-off (the interior point's dual is feasible only to its
// tolerance): the dual point is shrunk towards 0, (u, y) -> s (u, y) with the largest s in (0, 1] that puts
// every y_t in its box. A'y = H'u is linear, so s (u, y) is exactly dual feasible when every box of dom g*
// and dom f* contains 0 (l1, Huber, Vapnik, quantile, box, Gaussian): a true, slightly looser certificate.
template <int kN>
void ShrinkDualIntoDomain(const MapSmootherProblem& p, MapSmootherResult* res, Eigen::MatrixXd* y_lo) {
  const int T = p.T(), n = kN > 0 ? kN : p.state_dim(), nz = p.measurement_dim();
  double shrink = 1;
  bool zero_inside = true;
  for (int t = 0; t <= T; ++t) {
    const Penalty& f = p.ft(t);
    for (int i = 0; i < n; ++i) {
      const double v = res->y(i, t), lo = f.conjugate_lo()(i), hi = f.conjugate_hi()(i);
      if (v <= hi && v >= lo) continue;
      if (v - hi <= 1e-8 * (1 + std::abs(v)) && lo - v <= 1e-8 * (1 + std::abs(v))) continue;  // round-off
      if (lo > 0 || hi < 0) zero_inside = false;
      shrink = std::min(shrink, v > hi ? hi / v : lo / v);
    }
    for (int j = 0; j < nz; ++j)
      if (p.gt(t).conjugate_lo()(j) > 0 || p.gt(t).conjugate_hi()(j) < 0) zero_inside = false;
  }
  if (shrink < 1 && shrink > 0 && zero_inside) {
    res->u *= shrink;
    res->y *= shrink;
    *y_lo *= shrink;
  }
}

// y(u) outside dom f_t* by round-off is projected: the moved amount enters the bound as
// sum |x_t| |dy_t| (the size of x - x* taken as at most that of x, added to *error_bound); beyond 1e-8
// relative, no finite certificate (returns false).
template <int kN>
bool ProjectDualStates(const MapSmootherProblem& p, MapSmootherResult* res, Eigen::MatrixXd* y_lo,
                       double* error_bound) {
  const int n = kN > 0 ? kN : p.state_dim();
  bool certified = true;
  for (int t = 0; t <= p.T(); ++t) {
    const double before = res->y.col(t).cwiseAbs().maxCoeff();
    const double moved = ProjectIntoConjugateDomain(p.ft(t), res->y.col(t).data(), n, res);
    if (moved > 0) {
      y_lo->col(t).setZero();
      *error_bound += res->x.col(t).cwiseAbs().sum() * moved;
      if (moved > 1e-8 * (1 + before)) certified = false;
    }
  }
  return certified;
}

// Objectives and the gap as compensated sums of per-term values; S sums the magnitudes each term is
// computed from, for the running error bound gamma S (Higham, sec. 3.3).
template <int kN>
IDENT_SIMD_CLONES void EvaluateCertificate(const MapSmootherProblem& p, double z_scale, const Eigen::MatrixXd& r,
                                           const Eigen::MatrixXd& y_lo, double error_bound, bool certified,
                                           MapSmootherResult* res) {
  const int T = p.T(), n = kN > 0 ? kN : p.state_dim(), nz = p.measurement_dim();
  CompensatedSum primal, gap;
  double magnitudes = 0;
  const double domain_tolerance = 1e-8 * z_scale;
  for (int t = 0; t <= T; ++t) {
    const double fw = p.ft(t).Value(res->w.col(t), domain_tolerance);
    const double fs = p.ft(t).Conjugate(res->y.col(t));
    const double gr = p.gt(t).Value(r.col(t), domain_tolerance);
    const double gs = p.gt(t).Conjugate(res->u.col(t));
    DoubleDouble yw, ur;
    double yw_abs = 0, ur_abs = 0;
    for (int i = 0; i < n; ++i) {
      yw.AddProduct(res->y(i, t), res->w(i, t));
      yw.lo += y_lo(i, t) * res->w(i, t);
      yw_abs += std::abs(res->y(i, t) * res->w(i, t));
    }
    for (int j = 0; j < nz; ++j) {
      ur.AddProduct(res->u(j, t), r(j, t));
      ur_abs += std::abs(res->u(j, t) * r(j, t));
    }
    primal.Add(fw);
    primal.Add(gr);
    gap.Add(fw + fs - yw.value());  // f(w) + f*(y) - y'w >= 0   [Fenchel-Young]
    gap.Add(gr + gs - ur.value());  // g(r) + g*(u) - u'r >= 0
    magnitudes += std::abs(fw) + std::abs(fs) + yw_abs + std::abs(gr) + std::abs(gs) + ur_abs;
  }
  res->primal = primal.value();
  res->gap = gap.value();
  res->dual = res->primal - res->gap;
  if (!std::isfinite(res->dual)) {  // an infeasible x: D(u) evaluated directly
    CompensatedSum dual_sum;
    for (int t = 0; t <= T; ++t)
      dual_sum.Add(p.z.col(t).dot(res->u.col(t)) - p.gt(t).Conjugate(res->u.col(t)) - p.ft(t).Conjugate(res->y.col(t)));
    res->dual = dual_sum.value();
  }
  res->relative_gap = res->gap / std::max(1.0, std::abs(res->primal));
  res->gap_error_bound = 16 * (n + nz + 2) * kEps * magnitudes + error_bound + 4 * kEps * std::abs(res->gap);
  res->relative_gap_bound =
      certified && std::isfinite(res->gap) && std::isfinite(res->gap_error_bound)
          ? (std::max(res->gap, 0.0) + res->gap_error_bound) / std::max(1.0, std::abs(res->primal))
          : std::numeric_limits<double>::infinity();
}

// Reconstruction w_t in d f_t*(y_t), then x_0 = w_0, x_{t+1} = F_t x_t + w_{t+1}  [BCW sec. 3].
template <int kN>
void ReconstructFromDual(const MapSmootherProblem& p, double mu, MapSmootherResult* res) {
  const int T = p.T(), n = kN > 0 ? kN : p.state_dim();
  res->x_from_dual.resize(n, T + 1);
  res->nonunique_steps.clear();
  // The interior point locates a dual state that is degenerate on a kink of f_t* only to O(sqrt(mu)),
  // so kinks closer than y_tolerance count as reached.
  const double y_tolerance = std::max(1e-7, 100 * std::sqrt(std::max(mu, 0.0)));
  // and w_t = ∇f_t*(y_t) from the dual only to O(√mu) (relative): a primal w_t that far from it is the same point.
  const double w_tolerance = std::max(1e-6, std::sqrt(std::max(mu, 0.0)));
  for (int t = 0; t <= T; ++t) {
    const Penalty& f = p.ft(t);
    double* xt = res->x_from_dual.col(t).data();
    f.ConjugateGradient(res->y.col(t), res->x_from_dual.col(t));
    // d f_t*(y_t) is not a single point if (a) f_t* has a kink within y_tolerance of y_t, or (b) the
    // primal w_t (an element of d f_t*(y_t) at the optimum) differs from the element just chosen.
    double w_diff = 0, w_scale = 1;
    for (int i = 0; i < n; ++i) {
      w_diff = std::max(w_diff, std::abs(xt[i] - res->w(i, t)));
      w_scale = std::max({w_scale, std::abs(xt[i]), std::abs(res->w(i, t))});
    }
    const double y_scale = 1 + res->y.col(t).cwiseAbs().maxCoeff();
    if (!f.ConjugateIsDifferentiableNear(res->y.col(t), y_tolerance * y_scale) || w_diff > w_tolerance * w_scale)
      res->nonunique_steps.push_back(t);
    if (t > 0) AddMatVec<kN, kN>(p.Ft(t - 1).data(), n, n, xt - n, xt, 1.0);
  }
  res->reconstruction_unique = res->nonunique_steps.empty();
  res->max_abs_x_difference = (res->x_from_dual - res->x).cwiseAbs().maxCoeff();
}

// A dual point, its certificate and the states rebuilt from it: the fields of MapSmootherResult that CertifyDual
// and ReconstructFromDual set.
struct CertifiedDual {
  Eigen::MatrixXd u, y, x_from_dual;
  std::vector<int> nonunique_steps;
  double primal = 0, dual = 0, gap = 0, relative_gap = 0, gap_error_bound = 0, relative_gap_bound = 0;
  double dual_infeasibility = 0, max_abs_x_difference = 0;
  bool reconstruction_unique = false;

  void Swap(MapSmootherResult* res) {
    u.swap(res->u);
    y.swap(res->y);
    x_from_dual.swap(res->x_from_dual);
    nonunique_steps.swap(res->nonunique_steps);
    std::swap(primal, res->primal);
    std::swap(dual, res->dual);
    std::swap(gap, res->gap);
    std::swap(relative_gap, res->relative_gap);
    std::swap(gap_error_bound, res->gap_error_bound);
    std::swap(relative_gap_bound, res->relative_gap_bound);
    std::swap(dual_infeasibility, res->dual_infeasibility);
    std::swap(max_abs_x_difference, res->max_abs_x_difference);
    std::swap(reconstruction_unique, res->reconstruction_unique);
  }
};

// The dual point of res->u: u projected into dom g*, then y(u) in double-double (*y_lo its trailing parts).
// Returns the recursion's error bound on the gap.
template <int kN>
double DualPoint(const MapSmootherProblem& p, MapSmootherResult* res, Eigen::MatrixXd* y_lo) {
  for (int t = 0; t <= p.T(); ++t) ProjectIntoConjugateDomain(p.gt(t), res->u.col(t).data(), p.measurement_dim(), res);
  return DualStatesDoubleDouble<kN>(p, res, y_lo);
}

// y(u) shrunk or projected into dom f* (adding the projection's share to *error_bound); false if no finite
// certificate remains.
template <int kN>
bool DualIntoDomain(const MapSmootherProblem& p, MapSmootherResult* res, Eigen::MatrixXd* y_lo, double* error_bound) {
  ShrinkDualIntoDomain<kN>(p, res, y_lo);
  return ProjectDualStates<kN>(p, res, y_lo, error_bound);
}

// The certificate of the dual point (res->u, y(res->u)): the dual point, brought into dom f*, then the objectives
// and the certified gap. r: the measurement residuals z - Hx.
template <int kN>
void CertifyDual(const MapSmootherProblem& p, double z_scale, const Eigen::MatrixXd& r, MapSmootherResult* res) {
  Eigen::MatrixXd y_lo;
  double error_bound = DualPoint<kN>(p, res, &y_lo);
  const bool certified = DualIntoDomain<kN>(p, res, &y_lo, &error_bound);
  EvaluateCertificate<kN>(p, z_scale, r, y_lo, error_bound, certified, res);
}

// Everything of the result after the iteration, from res->x and res->u (see
// ident/smoothing/internal/map_smoother_fast_path.h): residuals, the dual point (u, y(u)) and its certificate,
// and the reconstruction of x from the dual. The iterate's own dual point is certified first; only if its
// certified relative gap exceeds `polish_above` (the residual R4 amplified by y(u)'s recursion) is it polished
// and certified again, and the tighter certificate is kept: both are true bounds. Two pairs of tasks that share
// nothing they write run side by side: the residuals and the dual point, then the certificate and the
// reconstruction (taken again after a polish, which changes y). The same numbers on one thread or two.
template <int kN>
void FinishResult(const MapSmootherProblem& p, double z_scale, double mu, double polish_above,
                  const MapSmootherDualIterate* dual, ForkJoin* fork, MapSmootherResult* res) {
  Eigen::MatrixXd r, y_lo;
  const Eigen::MatrixXd u_iterate = dual != nullptr ? res->u : Eigen::MatrixXd();
  double error_bound = 0;
  RunRethrowing(
      fork, [&] { PrimalResiduals<kN>(p, res, &r); }, [&] { error_bound = DualPoint<kN>(p, res, &y_lo); });
  const bool certified = DualIntoDomain<kN>(p, res, &y_lo, &error_bound);
  RunRethrowing(
      fork, [&] { EvaluateCertificate<kN>(p, z_scale, r, y_lo, error_bound, certified, res); },
      [&] { ReconstructFromDual<kN>(p, mu, res); });
  if (dual != nullptr && !(res->relative_gap_bound <= polish_above)) {
    CertifiedDual unpolished;
    unpolished.Swap(res);
    res->u = u_iterate;
    Eigen::MatrixXd v = dual->process_dual;
    PolishMapSmootherDual(p, *dual, &v, &res->u);
    CertifyDual<kN>(p, z_scale, r, res);
    if (res->relative_gap_bound <= unpolished.relative_gap_bound)
      ReconstructFromDual<kN>(p, mu, res);
    else
      unpolished.Swap(res);  // with the reconstruction from its y
  }
}

// A non-finite iterate (overflow or NaN in the iteration): nothing to evaluate, every figure NaN.
void MarkNotFinite(MapSmootherResult* res) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  res->status = MapSmootherStatus::kNumericalFailure;
  res->message = fmt::format(
      "the iterate is not finite after {} iterations (values too large or too far apart "
      "in scale: rescale the data or the model)",
      res->iterations);
  res->primal = res->dual = res->gap = res->relative_gap = res->dual_infeasibility = nan;
  res->gap_error_bound = res->relative_gap_bound = nan;
  res->max_abs_x_difference = nan;
  res->w.setConstant(res->x.rows(), res->x.cols(), nan);
  res->y.setConstant(res->x.rows(), res->x.cols(), nan);
  res->x_from_dual.setConstant(res->x.rows(), res->x.cols(), nan);
  res->nonunique_steps.clear();
  res->reconstruction_unique = false;
}

// The final status and message from the iteration's status and the certificate.
void SetStatusAndMessage(const MapSmootherOptions& options, MapSmootherResult* res) {
  // A converged iterate whose objectives overflow (e.g. the dual states y_t = F_t'y_{t+1} + H_t'u_t under
  // dynamics of 1e86) certifies nothing: reported as a numerical failure, never as converged.
  if (res->status == MapSmootherStatus::kConverged && !(std::isfinite(res->primal) && std::isfinite(res->dual))) {
    res->status = MapSmootherStatus::kNumericalFailure;
    res->message = fmt::format(
        "the objectives are not finite at the last iterate (primal {}, dual {}; values too large or too far apart "
        "in scale: rescale the data or the model)",
        res->primal, res->dual);
    return;
  }
  const std::string certificate = std::isfinite(res->relative_gap_bound)
                                      ? fmt::format("certified relative duality gap <= {:.1e}", res->relative_gap_bound)
                                      : std::string("no finite duality certificate: y(u) leaves dom f*");
  if (res->status == MapSmootherStatus::kConverged && !(res->relative_gap_bound <= options.gap_tolerance)) {
    res->status = MapSmootherStatus::kStalled;
    res->message = std::isfinite(res->relative_gap_bound)
                       ? fmt::format(
                             "stalled after {} iterations: the KKT conditions hold (residual {:.1e}), but the "
                             "{} exceeds gap_tolerance {:.1e}",
                             res->iterations, res->kkt_residual, certificate, options.gap_tolerance)
                       : fmt::format(
                             "stalled after {} iterations: the KKT conditions hold (residual {:.1e}), but "
                             "there is {}",
                             res->iterations, res->kkt_residual, certificate);
    return;
  }
  // The Newton matrix lost positive definiteness at an iterate that still carries a finite certificate:
  // the iteration reached its precision limit there — a stall at the certified accuracy, not a failure.
  if (res->status == MapSmootherStatus::kNumericalFailure && std::isfinite(res->relative_gap_bound)) {
    res->status = MapSmootherStatus::kStalled;
    res->message =
        fmt::format("stalled after {} iterations: the Newton matrix lost positive definiteness at KKT residual {:.1e}",
                    res->iterations, res->kkt_residual);
  }
  const std::string detail = res->message;  // what the iteration said about a stall or divergence
  switch (res->status) {
    case MapSmootherStatus::kConverged:
      res->message = fmt::format("converged in {} iterations (KKT residual {:.1e}; {})", res->iterations,
                                 res->kkt_residual, certificate);
      break;
    case MapSmootherStatus::kMaxIterations:
      res->message = fmt::format("did not converge in {} iterations: KKT residual {:.1e} above tolerance {:.1e} ({})",
                                 res->iterations, res->kkt_residual, options.tolerance, certificate);
      break;
    case MapSmootherStatus::kStalled:
      res->message = fmt::format("{}; {}", detail, certificate);
      break;
    case MapSmootherStatus::kInfeasible:
      res->message = detail;
      break;
    case MapSmootherStatus::kNumericalFailure:
      res->message = fmt::format("the Newton matrix is not positive definite after {} iterations (KKT residual {:.1e})",
                                 res->iterations, res->kkt_residual);
      break;
  }
}

}  // namespace

double MapSmootherDataUnit(const MapSmootherProblem& problem) {
  const Eigen::MatrixXd& z = problem.z;
  std::vector<double> steps;
  if (z.cols() > 1) {
    steps.reserve(static_cast<std::size_t>(z.rows()) * (z.cols() - 1));
    for (Eigen::Index t = 0; t + 1 < z.cols(); ++t)
      for (Eigen::Index i = 0; i < z.rows(); ++i) steps.push_back(std::abs(z(i, t + 1) - z(i, t)));
  }
  if (!steps.empty()) {
    const auto mid = steps.begin() + static_cast<std::ptrdiff_t>(steps.size() / 2);
    std::nth_element(steps.begin(), mid, steps.end());
    if (*mid > 0 && std::isfinite(*mid)) return *mid;
    double mean = 0;
    for (double d : steps) mean += d / static_cast<double>(steps.size());
    if (mean > 0 && std::isfinite(mean)) return mean;
  }
  const double largest = z.size() ? z.cwiseAbs().maxCoeff() : 0.0;
  if (largest > 0 && std::isfinite(largest)) return largest;
  // Measurements all zero: the penalties' own scale, the largest finite bound, offset or linear term of
  // their PLQ forms (all in the unit of the residuals).
  double bound = 0;
  auto take = [&](const Eigen::VectorXd& v) {
    for (double x : v)
      if (std::isfinite(x)) bound = std::max(bound, std::abs(x));
  };
  for (const std::vector<models::Penalty>* penalties : {&problem.process, &problem.measurement})
    for (const models::Penalty& f : *penalties) {
      take(f.plq().lo);
      take(f.plq().hi);
      take(f.plq().b);
      take(f.plq().p);
    }
  return bound > 0 ? bound : 1.0;
}

void FinishMapSmootherResult(const MapSmootherProblem& p, const MapSmootherOptions& options, double z_scale, double mu,
                             const MapSmootherDualIterate* dual, MapSmootherResult* res, ForkJoin* fork) {
  if (!res->x.allFinite() || !res->u.allFinite()) {
    MarkNotFinite(res);
    return;
  }
  // Polished above the solver's tolerance or the gap a converged result must certify, whichever is smaller.
  const double polish_above = std::min(options.tolerance, options.gap_tolerance);
  switch (p.state_dim()) {
    case 1:
      FinishResult<1>(p, z_scale, mu, polish_above, dual, fork, res);
      break;
    case 2:
      FinishResult<2>(p, z_scale, mu, polish_above, dual, fork, res);
      break;
    case 3:
      FinishResult<3>(p, z_scale, mu, polish_above, dual, fork, res);
      break;
    case 4:
      FinishResult<4>(p, z_scale, mu, polish_above, dual, fork, res);
      break;
    default:
      FinishResult<0>(p, z_scale, mu, polish_above, dual, fork, res);
  }
  SetStatusAndMessage(options, res);
}

bool StopsOnProgress(const MapSmootherOptions& options, int iteration, double kkt, const std::vector<double>& history,
                     double relative_floor, double state_size, MapSmootherResult* res) {
  if (kkt <= options.tolerance) {
    res->status = MapSmootherStatus::kConverged;
    return true;
  }
  if (iteration >= options.max_iterations) return true;
  if (iteration >= kStallWindow && kkt > kStallProgress * history[iteration - kStallWindow]) {
    res->status = MapSmootherStatus::kStalled;
    res->message = fmt::format(
        "stalled after {} iterations at KKT residual {:.1e} (no progress in the last {}; the residuals' "
        "round-off floor is {:.1e} for states of size {:.1e})",
        iteration, kkt, kStallWindow, relative_floor, state_size);
    return true;
  }
  return false;
}

void MarkDiverging(double u, int t, double ratio, MapSmootherResult* res) {
  res->status = MapSmootherStatus::kInfeasible;
  res->message = fmt::format(
      "infeasible: the multipliers diverge (|u| = {:.1e} at t = {}, {:.0e} times the penalties' bounds and "
      "the data): no state sequence keeps every residual inside its penalty's domain",
      u, t, ratio);
}

}  // namespace ident::internal
