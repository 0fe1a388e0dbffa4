#include "ident/smoothing/internal/interior_point.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include <fmt/format.h>

#include "ident/linalg/block_tridiagonal.h"
#include "ident/smoothing/internal/interior_point_newton.h"
#include "ident/smoothing/internal/interior_point_solver.h"
#include "ident/smoothing/internal/map_smoother_result.h"
#include "ident/smoothing/internal/small_kernels.h"

namespace ident::internal {
namespace interior_point {

template <int kN>
inline MapSmootherResult Solver<kN>::Run() {
  MapSmootherResult res;
  const double z_scale = 1 + z_.cwiseAbs().maxCoeff();
  const double bound_scale = BoundScale();
  BalanceOneSidedMultipliers();
  res.status = MapSmootherStatus::kMaxIterations;
  int iter = 0;
  // mu_scale: the complementarity at the start (at least 1). Multipliers × slacks carry the units of the
  // residuals (a domain bound 1000 away starts them 1000-fold), and so does the precision limit below.
  double mu = 0, mu_scale = 1;
  std::vector<double> history;  // KKT residual per iteration (stall test)
  history.reserve(static_cast<std::size_t>(o_.max_iterations) + 1);
  for (;; ++iter) {
    const double v_scale = Residuals();
    mu = num_constraints_ ? Complementarity(0) / num_constraints_ : 0.0;
    if (iter == 0) mu_scale = std::max(1.0, mu);
    double r4_floor = 0, x_scale = 0;
    const double kkt = KktResidual(v_scale, z_scale, bound_scale, mu, &r4_floor, &x_scale);
    res.kkt_residual = kkt;
    history.push_back(kkt);
    if (o_.on_iteration) o_.on_iteration(iter, kkt);
    if (Stops(iter, kkt, history, r4_floor / (v_scale * matrix_scale_), x_scale, bound_scale, z_scale, &res)) break;
    AssembleNewtonMatrix();
    if (!FactorizeBlockTridiagonal(n_, T_ + 1, D_.data(), E_.data(), C_.data(), G_.data(), chol_work_)) {
      // Near the solution K = M + D spans many orders of magnitude; if the Newton matrix breaks down
      // there, the iterate is accepted when its KKT residual is within 1e3 tolerance (precision limit).
      res.status =
          kkt <= 1e3 * o_.tolerance * mu_scale ? MapSmootherStatus::kConverged : MapSmootherStatus::kNumericalFailure;
      break;
    }
    NewtonStep(mu);
  }
  res.iterations = iter;
  Finish(&res, z_scale, mu);
  return res;
}

// The largest finite bound of the penalties' multipliers (at least 1).
template <int kN>
inline double Solver<kN>::BoundScale() const {
  double bound_scale = 1;
  for (int c : bounded_) {
    if (has_lo_[c]) bound_scale = std::max(bound_scale, std::abs(lo_(c)));
    if (has_hi_[c]) bound_scale = std::max(bound_scale, std::abs(hi_(c)));
  }
  return bound_scale;
}

// The relative KKT residual of the iterate after Residuals() (v_scale: its scale of p + B'u); also R4's
// round-off floor and the states' size.
template <int kN>
inline double Solver<kN>::KktResidual(double v_scale, double z_scale, double bound_scale, double mu,
                                      double* r4_floor_out, double* x_scale_out) const {
  const double r3max = r3_.size() ? r3_.cwiseAbs().maxCoeff() : 0.0;
  const double r4max = R4_.cwiseAbs().maxCoeff();
  // R4's round-off floor: the dual values c0 + W r of the quadratic terms are computed from residuals
  // r = x_t - F x_{t-1}, z_t - H x_t whose rounding is eps times the states' size, which for long
  // records (a double integrator: |x| ~ T^1.5) exceeds tolerance × the dual values. A residual at that
  // floor counts as met (the certificate of FinishMapSmootherResult measures the accuracy reached).
  const double x_scale = x_.cwiseAbs().maxCoeff();
  const double r4_floor = kFloorFactor * std::numeric_limits<double>::epsilon() * matrix_scale_ *
                          (constant_weight_scale_ * matrix_scale_ * (x_scale + z_scale) + v_scale);
  // The relative KKT residual: the complementarity s'q (the iterate's duality gap up to the residuals)
  // relative to the objective's size, since the unit σ need not be the residuals' size (a double
  // integrator's data steps are its velocity; 1e-12 per constraint stands in for an objective of zero);
  // R3 relative to the data; R4 relative to the dual values it sums (R4 sums products of H_t, F_t with
  // p + B'u), or its round-off floor.
  // R3 = B r - b - M u - (q_hi - q_lo) has a floor of eps times its largest term (multipliers of a
  // domain bound far from the residuals start large, BalanceOneSidedMultipliers).
  double qmax = 0;
  for (int c : bounded_) qmax = std::max({qmax, qlo_(c), qhi_(c)});
  const double r3_floor =
      kResidualFloorFactor * std::numeric_limits<double>::epsilon() * (z_scale * matrix_scale_ + bound_scale + qmax);
  *r4_floor_out = r4_floor;
  *x_scale_out = x_scale;
  return RelativeKktResidual(mu * num_constraints_, objective_scale_, num_constraints_,
                             r3max / std::max(1 + qmax, r3_floor / o_.tolerance),
                             r4max / std::max(v_scale * matrix_scale_, r4_floor / o_.tolerance));
}

// The stopping rule before a Newton step: converged, out of iterations, stalled (relative_floor: R4's
// round-off floor relative to the dual values), or diverging multipliers (beyond 1e10 times the bounds' and
// the data's size); sets res's status and message and returns true if the iteration stops.
template <int kN>
inline bool Solver<kN>::Stops(int iter, double kkt, const std::vector<double>& history, double relative_floor,
                              double x_scale, double bound_scale, double z_scale, MapSmootherResult* res) const {
  if (StopsOnProgress(o_, iter, kkt, history, relative_floor, sigma_ * x_scale, res)) return true;
  if (u_.size() && u_.cwiseAbs().maxCoeff() > 1e10 * bound_scale * z_scale) {
    Eigen::Index c = 0;
    const double umax = u_.cwiseAbs().maxCoeff(&c);
    int t = -1;
    for (const Term& term : active_)
      if (term.offset <= c && c < term.offset + term.prep->k) t = term.t;
    MarkDiverging(sigma_ * umax, t, umax / (bound_scale * z_scale), res);
    return true;
  }
  return false;
}

// One step on the factored Newton matrix.
template <int kN>
inline void Solver<kN>::NewtonStep(double mu) {
  if (num_constraints_ == 0) {  // all penalties quadratic: one Newton step solves (P) exactly
    Direction(0.0, false);
    Step(1.0);
    return;
  }
  // Mehrotra predictor-corrector: affine direction, centring sigma = (mu_aff / mu)^3, then the
  // corrected direction with the second-order term ds_aff .* dq_aff.
  Direction(0.0, false);
  const double alpha_aff = std::min(1.0, MaxStep());
  const double mu_aff = Complementarity(alpha_aff) / num_constraints_;
  const double sigma = std::pow(std::clamp(mu_aff / mu, 0.0, 1.0), 3);
  for (int c : bounded_) {
    xlo_(c) = dslo_(c) * dqlo_(c);
    xhi_(c) = dshi_(c) * dqhi_(c);
  }
  Direction(sigma * mu, true);
  Step(std::min(1.0, o_.step_fraction * MaxStep()));
}

// W = B'K^-1 B of a term at the current iterate (m x m, column-major), K = M + diag(q_hi/s_hi + q_lo/s_lo).
template <int kN>
inline void Solver<kN>::TermWeight(const Term& term, double* W) {
  Prepared& prep = *term.prep;
  const PlqForm& f = *prep.plq;
  const int m = prep.m, k = prep.k;
  if (prep.constant) {
    for (int i = 0; i < m * m; ++i) W[i] = prep.W.data()[i];
    return;
  }
  for (int i = 0; i < m * m; ++i) W[i] = 0;
  if (f.diagonal_M) {
    for (int i = 0; i < k; ++i) {
      const double inv = 1.0 / (BarrierCurvature(term.offset + i) + f.M(i, i));
      for (int b = 0; b < m; ++b)
        for (int a = 0; a < m; ++a) W[a + b * m] += f.B(i, a) * f.B(i, b) * inv;
    }
  } else {
    for (int i = 0; i < k; ++i) kd_(term.offset + i) = BarrierCurvature(term.offset + i);
    FactorK(term);
    prep.KinvB = prep.llt.solve(f.B);
    Eigen::Map<Eigen::MatrixXd>(W, m, m).noalias() = f.B.transpose() * prep.KinvB;
  }
}

// The dual value p + B'u of a term at the current iterate (constant terms: c0 + W r).
template <int kN>
inline void Solver<kN>::TermDual(const Term& term, double* out) {
  const Prepared& prep = *term.prep;
  const int m = prep.m;
  if (prep.constant) {
    double* r = r_.data();
    Residual(term, x_.data(), true, r);
    for (int i = 0; i < m; ++i) out[i] = prep.c0(i);
    AddMatVec(prep.W.data(), m, m, r, out, 1.0);
    return;
  }
  for (int i = 0; i < m; ++i) out[i] = prep.plq->p(i);
  AddMatTVec(prep.plq->B.data(), prep.k, m, u_.data() + term.offset, out, 1.0);
}

// The states, dual values and Newton weights of the iterate, back in the data's unit (dual values scale
// with σ, the weights not); the rest is common to both paths.
template <int kN>
inline void Solver<kN>::Finish(MapSmootherResult* res, double z_scale, double mu) {
  res->x = sigma_ * x_;
  res->u.resize(nz_, T_ + 1);
  MapSmootherDualIterate dual;
  dual.process_dual.resize(n_, T_ + 1);
  dual.process_weight.resize(n_ * n_, T_ + 1);
  dual.measurement_weight.resize(nz_ * nz_, T_ + 1);
  for (const Term& term : terms_) {
    const int t = term.t;
    if (term.process) {
      TermDual(term, dual.process_dual.col(t).data());
      TermWeight(term, dual.process_weight.col(t).data());
    } else {
      TermDual(term, res->u.col(t).data());  // u_t = p + B'u in d g_t
      TermWeight(term, dual.measurement_weight.col(t).data());
    }
  }
  res->u *= sigma_;
  dual.process_dual *= sigma_;
  FinishMapSmootherResult(p_, o_, sigma_ * z_scale, mu, &dual, res);
}

}  // namespace interior_point

namespace {

using interior_point::Solver;

template <int kN>
MapSmootherResult Solve(const MapSmootherProblem& problem, const MapSmootherOptions& options) {
  Solver<kN> solver(problem, options);
  return solver.Run();
}

}  // namespace

MapSmootherResult SolveMapSmootherInteriorPoint(const MapSmootherProblem& problem, const MapSmootherOptions& options) {
  switch (problem.state_dim()) {  // fixed-size kernels for small state dimensions
    case 1:
      return Solve<1>(problem, options);
    case 2:
      return Solve<2>(problem, options);
    case 3:
      return Solve<3>(problem, options);
    case 4:
      return Solve<4>(problem, options);
    default:
      return Solve<0>(problem, options);
  }
}

}  // namespace ident::internal
