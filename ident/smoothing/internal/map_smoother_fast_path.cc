#include "ident/smoothing/internal/map_smoother_fast_path.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <new>
#include <vector>

#include <Eigen/Cholesky>

#include <fmt/format.h>

#include "common/error.h"
#include "ident/linalg/internal/simd_clones.h"
#include "ident/linalg/work_arena.h"
#include "ident/smoothing/internal/map_smoother_fast_path_steps.h"
#include "ident/smoothing/internal/map_smoother_result.h"

namespace ident::internal {
namespace {

using fast_path::FillStepConstants;
using fast_path::Reciprocals;
using fast_path::SlackDirections;
using fast_path::StepConstants;
using fast_path::StepInverse;
using fast_path::StepState;
using models::Penalty;
using models::PlqForm;

bool HasFiniteBound(const PlqForm& f) { return f.lo.array().isFinite().any() || f.hi.array().isFinite().any(); }

// Scalar identity-B term with both bounds finite: rho(r) = sup_{lo <= u <= hi} { u r - 1/2 m u^2 }.
bool IsScalarBoxTerm(const Penalty& g) {
  const PlqForm& f = g.plq();
  return g.dim() == 1 && f.rows() == 1 && f.B(0, 0) == 1.0 && f.b(0) == 0.0 && f.p(0) == 0.0 &&
         std::isfinite(f.lo(0)) && std::isfinite(f.hi(0)) && f.M(0, 0) >= 0.0;
}

template <int kN>
class FastSolver {
 public:
  FastSolver(const MapSmootherProblem& p, const MapSmootherOptions& o)
      : p_(p), o_(o), T_(p.T()), sigma_(MapSmootherDataUnit(p)), z_(p.z.row(0).transpose() / sigma_) {
    invariant_ = p.F.size() == 1 && p.H.size() == 1 && p.process.size() <= 2 && p.measurement.size() == 1;
    // Bound-free process penalties: W = B'K^-1 B and c0 = p - B'K^-1 b, once per distinct penalty.
    std::vector<const Penalty*> seen;
    for (int t = 0; t <= T_ && (t < 2 || !invariant_); ++t) {
      const Penalty* f = &p.ft(t);
      if (std::find(seen.begin(), seen.end(), f) != seen.end()) continue;
      seen.push_back(f);
      const PlqForm& q = f->plq();
      Eigen::LLT<Eigen::MatrixXd> llt(q.M);
      IDENT_REQUIRE(llt.info() == Eigen::Success, "{} penalty: M must be positive definite without bounds", f->Name());
      const Eigen::MatrixXd KinvB = llt.solve(q.B);
      process_.push_back({f, q.B.transpose() * KinvB, (q.p - KinvB.transpose() * q.b) / sigma_});  // in the unit σ
    }
    const int num_constants = invariant_ ? std::min(T_ + 1, 3) : T_ + 1;
    constants_.resize(num_constants);
    for (int t = 0; t <= T_; ++t) {
      const int i = ConstantIndex(t);
      if (t == 0 || !invariant_ || (i == 1 && t == 1) || t == T_)
        FillStepConstants<kN>(p, t, Process(t).W, Process(t).c0, t < T_ ? &Process(t + 1).W : nullptr, sigma_,
                              &constants_[i]);
    }
    const std::size_t N = T_ + 1;
    const std::size_t state_doubles = (sizeof(StepState<kN>) + sizeof(double) - 1) / sizeof(double);
    arena_ = std::make_unique<WorkArena>(WorkArena::Padded(N * state_doubles) + WorkArena::Padded(N * kN));
    steps_ = reinterpret_cast<StepState<kN>*>(arena_->Take(N * state_doubles));
    for (std::size_t t = 0; t < N; ++t) new (&steps_[t]) StepState<kN>{};
    x_ = arena_->Take(N * kN);
    for (int t = 0; t <= T_; ++t) {  // strictly interior start, C'u + s = c exactly (as the general path)
      const StepConstants<kN>& c = constants_[ConstantIndex(t)];
      StepState<kN>& s = steps_[t];
      s.u = 0.5 * (c.lo + c.hi);
      s.slo = s.u - c.lo;
      s.shi = c.hi - s.u;
      s.qlo = s.qhi = 1.0;
      bound_scale_ = std::max({bound_scale_, std::abs(c.lo), std::abs(c.hi)});
    }
    for (const auto& F : p.F) matrix_scale_ = std::max(matrix_scale_, 1 + F.cwiseAbs().maxCoeff());
    for (const auto& H : p.H) matrix_scale_ = std::max(matrix_scale_, 1 + H.cwiseAbs().maxCoeff());
    for (const ProcessPenalty& f : process_) weight_scale_ = std::max(weight_scale_, f.W.cwiseAbs().maxCoeff());
  }

  MapSmootherResult Run() {
    MapSmootherResult res;
    const double z_scale = 1 + z_.cwiseAbs().maxCoeff();
    const double num_constraints = 2.0 * (T_ + 1);
    res.status = MapSmootherStatus::kMaxIterations;
    int iter = 0;
    double mu = 0, alpha = 0, mu_scale = 1;  // mu_scale: the general path's
    std::vector<double> history;               // KKT residual per iteration (stall test)
    history.reserve(static_cast<std::size_t>(o_.max_iterations) + 1);
    for (;; ++iter) {
      bool factored = false;  // the Newton matrix of the new iterate, factored in the same pass
      const Residuals r = StepResidualsAndFactor(alpha, &factored);
      mu = r.complementarity / num_constraints;
      if (iter == 0) mu_scale = std::max(1.0, mu);
      double r4_floor = 0;
      const double kkt = KktResidual(r, z_scale, num_constraints, &r4_floor);
      res.kkt_residual = kkt;
      history.push_back(kkt);
      if (o_.on_iteration) o_.on_iteration(iter, kkt);
      if (Stops(iter, kkt, r, r4_floor, z_scale, history, &res)) break;
      if (!factored) {  // as the general path: accept a breakdown at the precision limit
        res.status =
            kkt <= 1e3 * o_.tolerance * mu_scale ? MapSmootherStatus::kConverged : MapSmootherStatus::kNumericalFailure;
        break;
      }
      alpha = PredictorCorrector(r.complementarity, mu, num_constraints);
    }
    res.iterations = iter;
    Finish(z_scale, mu, &res);
    return res;
  }

 private:
  struct ProcessPenalty {
    const Penalty* penalty;
    Eigen::MatrixXd W;
    Eigen::VectorXd c0;
  };
  struct Residuals {
    double complementarity = 0, r3max = 0, r4max = 0, v_scale = 1, umax = 0, xmax = 0, objective_scale = 0, qmax = 0;
  };
  struct Backward {
    double max_step = std::numeric_limits<double>::infinity();
    double sum1 = 0, sum2 = 0;  // sum s.*dq + q.*ds, sum ds.*dq (complementarity after a step)
  };

  // R4's round-off floor (into *r4_floor) and the relative KKT residual: the general path's.
  double KktResidual(const Residuals& r, double z_scale, double num_constraints, double* r4_floor) const {
    *r4_floor = kFloorFactor * std::numeric_limits<double>::epsilon() * matrix_scale_ *
                (weight_scale_ * matrix_scale_ * (r.xmax + z_scale) + r.v_scale);
    return RelativeKktResidual(r.complementarity, r.objective_scale, num_constraints,
                               r.r3max / std::max(1 + r.qmax, kResidualFloorFactor * std::numeric_limits<double>::epsilon() *
                                                               (z_scale * matrix_scale_ + bound_scale_ + r.qmax) /
                                                               o_.tolerance),
                               r.r4max / std::max(r.v_scale * matrix_scale_, *r4_floor / o_.tolerance));
  }

  // The stopping rule before a Newton step (the general path's): converged, out of iterations, stalled, or
  // diverging multipliers; sets res's status and message and returns true if the iteration stops.
  bool Stops(int iter, double kkt, const Residuals& r, double r4_floor, double z_scale,
             const std::vector<double>& history, MapSmootherResult* res) const {
    if (StopsOnProgress(o_, iter, kkt, history, r4_floor / (r.v_scale * matrix_scale_), sigma_ * r.xmax, res))
      return true;
    if (r.umax > 1e10 * bound_scale_ * z_scale) {
      int t = 0;
      for (int s = 0; s <= T_; ++s)
        if (std::abs(steps_[s].u) > std::abs(steps_[t].u)) t = s;
      MarkDiverging(sigma_ * r.umax, t, r.umax / (bound_scale_ * z_scale), res);
      return true;
    }
    return false;
  }

  // Mehrotra predictor-corrector on the factored Newton matrix: affine direction, centring
  // sigma = (mu_aff / mu)^3, then the corrected direction with the second-order term ds_aff .* dq_aff.
  // Returns the step length of the corrected direction (applied by the next StepAndResiduals).
  double PredictorCorrector(double complementarity, double mu, double num_constraints) {
    const Backward affine = BackwardAndRecover(0.0, false);
    const double alpha_aff = std::min(1.0, affine.max_step);
    const double mu_aff = (complementarity + alpha_aff * (affine.sum1 + alpha_aff * affine.sum2)) / num_constraints;
    const double sigma = std::pow(std::clamp(mu_aff / mu, 0.0, 1.0), 3);
    CorrectorForward(sigma * mu);
    const Backward corrected = BackwardAndRecover(sigma * mu, true);
    return std::min(1.0, o_.step_fraction * corrected.max_step);
  }

  // The states and multipliers back in the data's unit, and the dual values and Newton weights of the
  // iterate for the certificate's dual polish: the process duals c0 + W r and their W, the measurement's
  // K^-1 = 1 / (m + q_lo/s_lo + q_hi/s_hi); then the common finish, with the step records released first
  // (they are most of the memory, and the finish allocates its own arrays).
  void Finish(double z_scale, double mu, MapSmootherResult* res) {
    res->x = sigma_ * Eigen::Map<const Eigen::MatrixXd>(x_, kN, T_ + 1);
    res->u.resize(1, T_ + 1);
    MapSmootherDualIterate dual;
    dual.process_dual.resize(kN, T_ + 1);
    // Time-invariant: one weight column per process penalty (ProcessWeightColumn).
    const int weight_columns = invariant_ ? std::min(static_cast<int>(p_.process.size()), T_ + 1) : T_ + 1;
    dual.process_weight.resize(kN * kN, weight_columns);
    dual.measurement_weight.resize(1, T_ + 1);
    for (int t = 0; t <= T_; ++t) {
      const StepConstants<kN>& c = Constants(t);
      const StepState<kN>& s = steps_[t];
      res->u(0, t) = sigma_ * s.u;  // p + B'u = u (identity B, p = 0)
      const double* xt = x_ + t * kN;
      double w[kN];
      for (int i = 0; i < kN; ++i) w[i] = xt[i];
      if (t > 0)
        for (int j = 0; j < kN; ++j)
          for (int i = 0; i < kN; ++i) w[i] -= c.F[i + j * kN] * xt[j - kN];
      for (int i = 0; i < kN; ++i) {
        double v = c.c0[i];
        for (int j = 0; j < kN; ++j) v += c.W[i + j * kN] * w[j];
        dual.process_dual(i, t) = sigma_ * v;
      }
      if (t < weight_columns || !invariant_)
        for (int i = 0; i < kN * kN; ++i) dual.process_weight(i, ProcessWeightColumn(dual.process_weight, t)) = c.W[i];
      dual.measurement_weight(0, t) = 1.0 / (c.m + s.qlo / s.slo + s.qhi / s.shi);
    }
    steps_ = nullptr;
    x_ = nullptr;
    arena_.reset();
    FinishMapSmootherResult(p_, o_, sigma_ * z_scale, mu, &dual, res);
  }

  int ConstantIndex(int t) const {
    if (!invariant_) return t;
    return t == 0 ? 0 : t == T_ ? std::min(T_, 2) : 1;
  }

  const ProcessPenalty& Process(int t) const {
    const Penalty* f = &p_.ft(t);
    for (const ProcessPenalty& q : process_)
      if (q.penalty == f) return q;
    return process_.front();  // not reached: every f_t was prepared
  }

  const StepConstants<kN>& Constants(int t) const { return constants_[ConstantIndex(t)]; }

  // Every pass keeps the values it carries from one step to the next (x_{t-1}, P_{t-1}, v_{t-1}, dx_{t+1}) and the
  // values it computes for the current step in locals, and reads from the step records only what an earlier
  // pass wrote: a vector load of a field written by scalar stores a few instructions earlier cannot be
  // forwarded from the store buffer and stalls the recurrence.

  // Applies the pending step x, u, s, q += alpha d (alpha = 0: none), then R3 = r - m u - (q_hi - q_lo) and
  // R4 = sum J'(p + B'u) (process: c0 + W r on x_t - F x_{t-1}; measurement: -H'u), and, one step behind
  // (R4_{t-1} is complete at step t), the factorisation and forward substitution of the new iterate
  // (FactorStep), in one forward pass: at large T the passes stream the step records from memory, and this
  // saves one. *factored: false if a Schur complement is not numerically positive definite (the
  // factorisation stops there; the residuals are complete).
  IDENT_SIMD_CLONES Residuals StepResidualsAndFactor(double alpha, bool* factored) {
    Residuals out;
    double xp[kN] = {}, R4p[kN] = {};  // x_{t-1}, and R4_{t-1} until F_{t-1}' v_t completes it
    double r3p = 0;                    // R3_{t-1}
    double Pp[kN * kN] = {}, vp[kN] = {};  // the factorisation's P_{t-1} and v_{t-1}
    bool ok = true;
    for (int t = 0; t <= T_; ++t) {
      const StepConstants<kN>& c = Constants(t);
      StepState<kN>& s = steps_[t];
      double* xt = x_ + t * kN;
      double x[kN];
      for (int i = 0; i < kN; ++i) x[i] = xt[i];
      double u = s.u, slo = s.slo, shi = s.shi, qlo = s.qlo, qhi = s.qhi;
      if (alpha > 0) {
        double dslo, dshi;
        SlackDirections(c, s, s.du, &dslo, &dshi);
        for (int i = 0; i < kN; ++i) xt[i] = x[i] += alpha * s.dx[i];
        s.u = u += alpha * s.du;
        s.slo = slo += alpha * dslo;
        s.shi = shi += alpha * dshi;
        s.qlo = qlo += alpha * s.dqlo;
        s.qhi = qhi += alpha * s.dqhi;
      }
      double r[kN], v[kN];
      for (int i = 0; i < kN; ++i) r[i] = x[i];
      if (t > 0)
        for (int j = 0; j < kN; ++j)
          for (int i = 0; i < kN; ++i) r[i] -= c.F[i + j * kN] * xp[j];
      for (int i = 0; i < kN; ++i) v[i] = c.c0[i];
      for (int j = 0; j < kN; ++j)
        for (int i = 0; i < kN; ++i) v[i] += c.W[i + j * kN] * r[j];
      double hx = 0, R4[kN];
      for (int i = 0; i < kN; ++i) {
        out.objective_scale += std::abs(v[i] * r[i]);
        out.xmax = std::max(out.xmax, std::abs(x[i]));
        out.v_scale = std::max(out.v_scale, std::abs(v[i]));
        R4[i] = v[i] - c.H[i] * u;
        hx += c.H[i] * x[i];
      }
      if (t > 0) {  // R4_{t-1} -= F_{t-1}' v: now complete, and step t - 1 can be factored
        double R4c[kN];
        for (int j = 0; j < kN; ++j) {
          double fv = 0;
          for (int i = 0; i < kN; ++i) fv += c.F[i + j * kN] * v[i];
          R4c[j] = R4p[j] - fv;
          out.r4max = std::max(out.r4max, std::abs(R4c[j]));
        }
        if (ok) ok = FactorStep(t - 1, R4c, r3p, Pp, vp);
      }
      for (int i = 0; i < kN; ++i) {
        R4p[i] = R4[i];
        xp[i] = x[i];
      }
      const double au = std::abs(u);
      out.v_scale = std::max(out.v_scale, au);
      out.umax = std::max(out.umax, au);
      const double r3 = z_[t] - hx - c.m * u - (qhi - qlo);
      r3p = r3;
      out.r3max = std::max(out.r3max, std::abs(r3));
      out.objective_scale += std::abs(u * (z_[t] - hx));
      out.complementarity += slo * qlo + shi * qhi;
      out.qmax = std::max({out.qmax, qlo, qhi});
    }
    for (int i = 0; i < kN; ++i) out.r4max = std::max(out.r4max, std::abs(R4p[i]));
    if (ok) ok = FactorStep(T_, R4p, r3p, Pp, vp);
    *factored = ok;
    return out;
  }

  // rt3 = R3 - e,  e = S_hi^-1 (-R2_hi + Q_hi R1_hi) - S_lo^-1 (-R2_lo + Q_lo R1_lo)  (general path's
  // RightHandSide), then v_t = P_t (b_t - E_t v_{t-1}) = P_t b_t - M_t v_{t-1} with b_t = -R4_t + H' K^-1 rt3,
  // where P_t H' K^-1 rt3 = rt3 gf exactly (no product with the large K^-1); the predictor's R2 = s .* q.
  // P_t = S_t^-1, S_t = D_t - E_t P_{t-1} E_t'. Stores rt3 and v_t, also in v (which may be v_prev).
  [[gnu::always_inline]] inline void ForwardRightHandSide(const StepConstants<kN>& c, StepState<kN>& s,
                                                          const double* R4, double r3, const double* P, const double* M,
                                                          const double* gf, double islo, double ishi,
                                                          const double* v_prev, double* v) {
    const double u = s.u, slo = s.slo, shi = s.shi, qlo = s.qlo, qhi = s.qhi;
    const double r1hi = u + shi - c.hi, r1lo = -u + slo + c.lo;
    const double r2lo = slo * qlo, r2hi = shi * qhi;
    const double e = (-r2hi + qhi * r1hi) * ishi - (-r2lo + qlo * r1lo) * islo;
    const double rt3 = r3 - e;
    double vt[kN];
    for (int i = 0; i < kN; ++i) {
      double pb = P[i] * R4[0];  // the sums start at their first term: no + 0.0 (which does not fold)
      for (int k = 1; k < kN; ++k) pb += P[i + k * kN] * R4[k];
      vt[i] = rt3 * gf[i] - pb;
    }
    if (v_prev)  // the recurrence: one level of products
      for (int i = 0; i < kN; ++i) {
        double mv = M[i] * v_prev[0];
        for (int k = 1; k < kN; ++k) mv += M[i + k * kN] * v_prev[k];
        vt[i] -= mv;
      }
    for (int i = 0; i < kN; ++i) s.v[i] = v[i] = vt[i];
    s.rt3 = rt3;
  }

  // Step t of the block LDL' of the Newton matrix (D_t = Db_t + K^-1 H'H, E_t) fused with the predictor's
  // forward substitution: A = L diag(S_t) L' with L_t = E_t P_{t-1}; the solves use v_t = P_t y_t, so that L is
  // not stored and the large K^-1 of coordinates at a kink never multiplies a vector. R4 = R4_t, r3 = R3_t; Pp and vp
  // carry P_{t-1} and v_{t-1} in and P_t and v_t out. False if the Schur complement S_t is not numerically
  // positive definite.
  [[gnu::always_inline]] inline bool FactorStep(int t, const double* R4, double r3, double* Pp, double* vp) {
    const StepConstants<kN>& c = Constants(t);
    StepState<kN>& s = steps_[t];
    Reciprocals(s);
    const double islo = s.islo, ishi = s.ishi;
    const double ikd = c.m + s.qlo * islo + s.qhi * ishi;  // K = M + D, D = q/s (barrier curvature)
    const double kd = 1.0 / ikd;
    s.kd = kd;
    // P_t = S_t^-1 with the measurement's rank-one term entering with the factor K (StepInverse).
    double P[kN * kN], gf[kN];
    if (!StepInverse<kN>(c, t > 0 ? Pp : nullptr, ikd, kd, P, gf)) return false;
    // M_t = P_t E_t: the forward recurrence then takes one product level. P_t is stored (not M_t and
    // P_t E_{t+1}', twice its size): at large T the passes stream the step records from memory.
    double M[kN * kN];
    for (int j = 0; j < kN; ++j)
      for (int i = 0; i < kN; ++i) {
        double m = P[i] * c.E[j * kN];
        for (int k = 1; k < kN; ++k) m += P[i + k * kN] * c.E[k + j * kN];
        M[i + j * kN] = m;
      }
    for (int i = 0; i < kN * kN; ++i) s.P[i] = Pp[i] = P[i];
    for (int i = 0; i < kN; ++i) s.gf[i] = gf[i];
    ForwardRightHandSide(c, s, R4, r3, P, M, gf, islo, ishi, t > 0 ? vp : nullptr, vp);
    return true;
  }

  // The corrector's right-hand side differs from the predictor's only in R2, by -target + ds_aff .* dq_aff:
  // rt3 changes by d_t = (target - ds_lo dq_lo) / s_lo - (target - ds_hi dq_hi) / s_hi and, the forward
  // substitution being linear, v_t by dv_t = d_t gf_t - P_t E_t dv_{t-1} (no products with R4_t).
  IDENT_SIMD_CLONES void CorrectorForward(double target) {
    double dvp[kN] = {};
    for (int t = 0; t <= T_; ++t) {
      const StepConstants<kN>& c = Constants(t);
      StepState<kN>& s = steps_[t];
      double dslo, dshi;
      SlackDirections(c, s, s.du, &dslo, &dshi);
      const double d = (target - dslo * s.dqlo) * s.islo - (target - dshi * s.dqhi) * s.ishi;
      double ev[kN];  // E_t dv_{t-1}
      for (int i = 0; i < kN; ++i) {
        double e = c.E[i] * dvp[0];
        for (int k = 1; k < kN; ++k) e += c.E[i + k * kN] * dvp[k];
        ev[i] = e;
      }
      double dv[kN];
      for (int i = 0; i < kN; ++i) {
        double mv = s.P[i] * ev[0];
        for (int k = 1; k < kN; ++k) mv += s.P[i + k * kN] * ev[k];
        dv[i] = d * s.gf[i] - mv;
      }
      for (int i = 0; i < kN; ++i) {
        s.v[i] += dv[i];
        dvp[i] = dv[i];
      }
      s.rt3 += d;
    }
  }

  // dx_t = v_t - P_t E_{t+1}' dx_{t+1} (backward substitution), then du = K^-1 (rt3 - H dx),
  // ds, dq (general path's Direction), the largest step keeping s, q > 0 and the complementarity sums.
  IDENT_SIMD_CLONES Backward BackwardAndRecover(double target, bool corrector) {
    Backward out;
    double max_ratio = 0;  // max -d/v over components: the step limit is 1 / max_ratio
    double dxn[kN] = {};   // dx_{t+1}
    for (int t = T_; t >= 0; --t) {
      const StepConstants<kN>& c = Constants(t);
      StepState<kN>& s = steps_[t];
      double dx[kN];
      for (int i = 0; i < kN; ++i) dx[i] = s.v[i];
      if (t < T_) {
        const double* En = Constants(t + 1).E;
        double ex[kN];  // E_{t+1}' dx_{t+1}
        for (int i = 0; i < kN; ++i) {
          double e = En[i * kN] * dxn[0];
          for (int k = 1; k < kN; ++k) e += En[k + i * kN] * dxn[k];
          ex[i] = e;
        }
        for (int i = 0; i < kN; ++i) {
          double nd = s.P[i] * ex[0];
          for (int k = 1; k < kN; ++k) nd += s.P[i + k * kN] * ex[k];
          dx[i] -= nd;
        }
      }
      double hdx = 0;
      for (int i = 0; i < kN; ++i) {
        s.dx[i] = dxn[i] = dx[i];
        hdx += c.H[i] * dx[i];
      }
      const double u = s.u, slo = s.slo, shi = s.shi, qlo = s.qlo, qhi = s.qhi;
      const double islo = s.islo, ishi = s.ishi;
      const double du = s.kd * (s.rt3 - hdx);
      const double r1hi = u + shi - c.hi, r1lo = -u + slo + c.lo;
      double r2lo = slo * qlo - target, r2hi = shi * qhi - target;
      if (corrector) {  // the affine direction's ds .* dq
        const double du_affine = s.du;
        r2lo += (-r1lo + du_affine) * s.dqlo;
        r2hi += (-r1hi - du_affine) * s.dqhi;
      }
      const double dshi = -r1hi - du, dslo = -r1lo + du;  // SlackDirections
      const double dqhi = (-r2hi - qhi * dshi) * ishi, dqlo = (-r2lo - qlo * dslo) * islo;
      s.du = du;
      s.dqhi = dqhi;
      s.dqlo = dqlo;
      max_ratio = std::max({max_ratio, -dslo * islo, -dshi * ishi, -dqlo * s.iqlo, -dqhi * s.iqhi});
      if (!corrector) {
        out.sum1 += slo * dqlo + qlo * dslo + shi * dqhi + qhi * dshi;
        out.sum2 += dslo * dqlo + dshi * dqhi;
      }
    }
    if (max_ratio > 0) out.max_step = 1.0 / max_ratio;
    return out;
  }

  const MapSmootherProblem& p_;
  const MapSmootherOptions& o_;
  const int T_;
  bool invariant_ = false;  // one F, one H, f_0 and one f, one g: three step-constant records
  std::vector<ProcessPenalty> process_;
  std::vector<StepConstants<kN>> constants_;
  std::unique_ptr<WorkArena> arena_;
  StepState<kN>* steps_ = nullptr;
  double* x_ = nullptr;      // kN x (T+1)
  const double sigma_;       // the data unit (MapSmootherDataUnit)
  const Eigen::VectorXd z_;  // the measurements in that unit
  double bound_scale_ = 1, matrix_scale_ = 1;
  double weight_scale_ = 0;  // max |W| of the process penalties (R4's round-off floor)
};

}  // namespace

bool MapSmootherFastPathApplies(const MapSmootherProblem& p) {
  const int n = p.state_dim();
  if (n < 1 || n > 4 || p.measurement_dim() != 1) return false;
  for (const Penalty& f : p.process)
    if (HasFiniteBound(f.plq())) return false;
  for (const Penalty& g : p.measurement)
    if (!IsScalarBoxTerm(g)) return false;
  return true;
}

MapSmootherResult SolveMapSmootherFastPath(const MapSmootherProblem& p, const MapSmootherOptions& o) {
  switch (p.state_dim()) {
    case 1:
      return FastSolver<1>(p, o).Run();
    case 2:
      return FastSolver<2>(p, o).Run();
    case 3:
      return FastSolver<3>(p, o).Run();
    default:
      return FastSolver<4>(p, o).Run();
  }
}

}  // namespace ident::internal
