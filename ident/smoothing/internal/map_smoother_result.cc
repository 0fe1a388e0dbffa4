#include "ident/smoothing/internal/map_smoother_result.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include <fmt/format.h>

#include "common/error.h"
#include "ident/smoothing/internal/small_kernels.h"

namespace ident::internal {
namespace {

using models::Penalty;

// Everything of the result after the iteration, from res->x and res->u (see
// ident/smoothing/internal/map_smoother_fast_path.h).
template <int kN>
void FinishResult(const MapSmootherProblem& p, double z_scale, double mu, MapSmootherResult* res) {
  const int T = p.T(), n = kN > 0 ? kN : p.state_dim(), nz = p.measurement_dim();
  res->w.resize(n, T + 1);
  for (int t = 0; t <= T; ++t) {  // w_t = x_t - F_{t-1} x_{t-1}
    double* wt = res->w.col(t).data();
    const double* xt = res->x.col(t).data();
    for (int i = 0; i < n; ++i) wt[i] = xt[i];
    if (t > 0) AddMatVec<kN, kN>(p.Ft(t - 1).data(), n, n, xt - n, wt, -1.0);
  }
  // Dual point: u from the multipliers, y from u by the dynamics of (D) (exact A'y = H'u). Rounding can
  // leave u_t, y_t a hair outside a box dom f*, dom g*: the distance is reported and the point projected.
  auto project = [&](const Penalty& pen, double* v, int size) {
    double violation = 0;
    for (int i = 0; i < size; ++i) {
      const double c = std::clamp(v[i], pen.conjugate_lo()(i), pen.conjugate_hi()(i));
      violation = std::max(violation, std::abs(c - v[i]));
      v[i] = c;
    }
    res->dual_infeasibility = std::max(res->dual_infeasibility, violation);
  };
  for (int t = 0; t <= T; ++t) project(p.gt(t), res->u.col(t).data(), nz);
  res->y.resize(n, T + 1);
  for (int t = T; t >= 0; --t) {  // y_T = H_T'u_T, y_t = F_t'y_{t+1} + H_t'u_t   [BCW Thm 2.5, A'y = H'u]
    double* yt = res->y.col(t).data();
    for (int i = 0; i < n; ++i) yt[i] = 0;
    if (t < T) AddMatTVec<kN, kN>(p.Ft(t).data(), n, n, yt + n, yt, 1.0);
    AddMatTVec<0, kN>(p.Ht(t).data(), nz, n, res->u.col(t).data(), yt, 1.0);
  }
  for (int t = 0; t <= T; ++t) project(p.ft(t), res->y.col(t).data(), n);
  double dual = 0, primal = 0;
  const double domain_tolerance = 1e-8 * z_scale;
  Eigen::VectorXd residual(nz);
  double* r = residual.data();
  for (int t = 0; t <= T; ++t) {
    dual += p.z.col(t).dot(res->u.col(t)) - p.gt(t).Conjugate(res->u.col(t)) - p.ft(t).Conjugate(res->y.col(t));
    for (int i = 0; i < nz; ++i) r[i] = p.z(i, t);  // z_t - H_t x_t
    AddMatVec<0, kN>(p.Ht(t).data(), nz, n, res->x.col(t).data(), r, -1.0);
    primal += p.ft(t).Value(res->w.col(t), domain_tolerance) +
              p.gt(t).Value(Eigen::Map<const Eigen::VectorXd>(r, nz), domain_tolerance);
  }
  res->dual = dual;
  res->primal = primal;
  res->gap = res->primal - res->dual;
  res->relative_gap = res->gap / std::max(1.0, std::abs(res->primal));
  // Reconstruction w_t in d f_t*(y_t), then x_0 = w_0, x_{t+1} = F_t x_t + w_{t+1}  [BCW sec. 3].
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

void FinishMapSmootherResult(const MapSmootherProblem& p, double z_scale, double mu, MapSmootherResult* res) {
  if (!res->x.allFinite() || !res->u.allFinite()) {  // overflow or NaN in the iteration: nothing to evaluate
    const double nan = std::numeric_limits<double>::quiet_NaN();
    res->status = MapSmootherStatus::kNumericalFailure;
    res->message = fmt::format(
        "the iterate is not finite after {} iterations (values too large or too far apart "
        "in scale: rescale the data or the model)",
        res->iterations);
    res->primal = res->dual = res->gap = res->relative_gap = res->dual_infeasibility = nan;
    res->max_abs_x_difference = nan;
    res->w.setConstant(res->x.rows(), res->x.cols(), nan);
    res->y.setConstant(res->x.rows(), res->x.cols(), nan);
    res->x_from_dual.setConstant(res->x.rows(), res->x.cols(), nan);
    res->nonunique_steps.clear();
    res->reconstruction_unique = false;
    return;
  }
  switch (p.state_dim()) {
    case 1:
      FinishResult<1>(p, z_scale, mu, res);
      break;
    case 2:
      FinishResult<2>(p, z_scale, mu, res);
      break;
    case 3:
      FinishResult<3>(p, z_scale, mu, res);
      break;
    case 4:
      FinishResult<4>(p, z_scale, mu, res);
      break;
    default:
      FinishResult<0>(p, z_scale, mu, res);
  }
  // A converged iterate whose objectives overflow (e.g. the dual states y_t = F_t'y_{t+1} + H_t'u_t under
  // dynamics of 1e86) certifies nothing: reported as a numerical failure, never as converged.
  if (res->status == MapSmootherStatus::kConverged && !(std::isfinite(res->primal) && std::isfinite(res->dual))) {
    res->status = MapSmootherStatus::kNumericalFailure;
    res->message = fmt::format(
        "the objectives are not finite at the last iterate (primal {}, dual {}; values too large or too far apart "
        "in scale: rescale the data or the model)",
        res->primal, res->dual);
  }
}

void SetMapSmootherMessage(MapSmootherResult* res) {
  switch (res->status) {
    case MapSmootherStatus::kConverged:
      res->message =
          fmt::format("converged in {} iterations (KKT residual {:.1e})", res->iterations, res->kkt_residual);
      break;
    case MapSmootherStatus::kMaxIterations:
      res->message = fmt::format("did not converge in {} iterations (the problem may be infeasible)", res->iterations);
      break;
    case MapSmootherStatus::kInfeasible:
      res->message = "the multipliers diverge: no state sequence keeps every residual inside its penalty's domain";
      break;
    case MapSmootherStatus::kNumericalFailure:
      res->message = "the Newton matrix is not positive definite";
      break;
  }
}

}  // namespace ident::internal
