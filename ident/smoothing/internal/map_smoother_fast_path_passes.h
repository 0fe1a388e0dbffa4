// The passes of the MAP smoother's fast path over its step records (internal to
// ident/smoothing/internal/map_smoother_fast_path.cc; the solver is map_smoother_fast_path_solver.h).
//
// The passes run over the top half t < m from the start and over the bottom half t > m from the end (on two
// threads when fork_ has a worker), then over the middle step m = T/2: the factorisation eliminates from both ends
// and meets at m (a twisted factorisation), and the substitutions start at m. Every pass keeps the values it
// carries from one step to the next in locals, and reads from the step records only what an earlier pass wrote.
#pragma once

#include <algorithm>
#include <cmath>

#include "ident/linalg/internal/simd_clones.h"
#include "ident/smoothing/internal/map_smoother_fast_path_solver.h"
#include "ident/smoothing/internal/map_smoother_fast_path_steps.h"

namespace ident::internal::fast_path {

// The pending step x, u, s, q += alpha d of step t (alpha = 0: none); x only if with_x.
template <int kN>
[[gnu::always_inline]] inline void FastSolver<kN>::ApplyStep(int t, double alpha, bool with_x) {
  if (!(alpha > 0)) return;
  const StepConstants<kN>& c = Constants(t);
  StepState<kN>& s = steps_[t];
  double dslo, dshi;
  SlackDirections(c, s, s.du, &dslo, &dshi);
  if (with_x)
    for (int i = 0; i < kN; ++i) x_[t * kN + i] += alpha * s.dx[i];
  s.u += alpha * s.du;
  s.slo += alpha * dslo;
  s.shi += alpha * dshi;
  s.qlo += alpha * s.dqlo;
  s.qhi += alpha * s.dqhi;
}

// The residual terms of step t at the (stepped) iterate, from x = x_t and xp = x_{t-1} (nullptr at t = 0): the
// process dual vd = c0 + W (x_t - F x_{t-1}), R4o = vd - H'u (R4_t = R4o - F_t' vd_{t+1}), R3 = r - m u - (q_hi -
// q_lo), and the step's share of the sums and maxima of `out`.
template <int kN>
[[gnu::always_inline]] inline double FastSolver<kN>::StepResidual(int t, const double* x, const double* xp, double* vd,
                                                                  double* R4o, Residuals* out) const {
  const StepConstants<kN>& c = Constants(t);
  const StepState<kN>& s = steps_[t];
  double r[kN];
  ProcessDual(c, x, xp, r, vd);
  const double u = s.u;
  double hx = 0;
  for (int i = 0; i < kN; ++i) {
    out->objective_scale += std::abs(vd[i] * r[i]);
    out->xmax = std::max(out->xmax, std::abs(x[i]));
    out->v_scale = std::max(out->v_scale, std::abs(vd[i]));
    R4o[i] = vd[i] - c.H[i] * u;
    hx += c.H[i] * x[i];
  }
  const double au = std::abs(u);
  out->v_scale = std::max(out->v_scale, au);
  out->umax = std::max(out->umax, au);
  const double r3 = z_[t] - hx - c.m * u - (s.qhi - s.qlo);
  out->r3max = std::max(out->r3max, std::abs(r3));
  out->objective_scale += std::abs(u * (z_[t] - hx));
  out->complementarity += s.slo * s.qlo + s.shi * s.qhi;
  out->qmax = std::max({out->qmax, s.qlo, s.qhi});
  return r3;
}

// R4 -= F' vd (F = F_t of Constants(t + 1), vd = vd_{t+1}): R4_t complete.
template <int kN>
[[gnu::always_inline]] inline void FastSolver<kN>::CompleteR4(int t, const double* vd_next, double* R4,
                                                              Residuals* out) const {
  const double* F = Constants(t + 1).F;
  for (int j = 0; j < kN; ++j) {
    double fv = 0;
    for (int i = 0; i < kN; ++i) fv += F[i + j * kN] * vd_next[i];
    R4[j] -= fv;
    out->r4max = std::max(out->r4max, std::abs(R4[j]));
  }
}

// Applies the pending step (alpha > 0), then the residuals R3, R4 and the complementarity of the iterate and the
// factorisation and forward substitutions of its Newton matrix, in one pass over each half and the middle: at
// large T the passes stream the step records from memory. *factored: false if a Schur complement is not
// numerically positive definite (the residuals are complete).
template <int kN>
inline typename FastSolver<kN>::Residuals FastSolver<kN>::StepResidualsAndFactor(double alpha, bool* factored) {
  const int m = Middle();
  ApplyStep(m, alpha, true);
  Residuals top, bottom, out;
  bool top_ok = true, bottom_ok = true;
  double vd_below[kN] = {};  // vd_{m+1}
  fork_.Run([&] { top = TopForward(alpha, &top_ok); }, [&] { bottom = BottomForward(alpha, vd_below, &bottom_ok); });
  out = Combine(top, bottom);
  const double* xm = x_ + m * kN;
  double vd[kN], R4[kN];
  const double r3 = StepResidual(m, xm, m > 0 ? xm - kN : nullptr, vd, R4, &out);
  if (m < T_)
    CompleteR4(m, vd_below, R4, &out);
  else
    for (int i = 0; i < kN; ++i) out.r4max = std::max(out.r4max, std::abs(R4[i]));
  *factored = top_ok && bottom_ok && FactorStep(m, R4, r3, m > 0, m < T_, nullptr, nullptr);
  return out;
}

template <int kN>
inline typename FastSolver<kN>::Residuals FastSolver<kN>::Combine(const Residuals& a, const Residuals& b) {
  Residuals r;
  r.complementarity = a.complementarity + b.complementarity;
  r.objective_scale = a.objective_scale + b.objective_scale;
  r.r3max = std::max(a.r3max, b.r3max);
  r.r4max = std::max(a.r4max, b.r4max);
  r.v_scale = std::max(a.v_scale, b.v_scale);
  r.umax = std::max(a.umax, b.umax);
  r.xmax = std::max(a.xmax, b.xmax);
  r.qmax = std::max(a.qmax, b.qmax);
  return r;
}

// Top half, t = 0 … m-1: step, residuals, and (one step behind, R4_{t-1} being complete at step t) the
// factorisation from the start, the last step's R4 completed with vd_m.
template <int kN>
IDENT_SIMD_CLONES inline typename FastSolver<kN>::Residuals FastSolver<kN>::TopForward(double alpha, bool* factored) {
  Residuals out;
  const int m = Middle();
  if (m == 0) return out;
  bool ok = true;  // on this thread's stack, as `out`: the halves' results would share a cache line
  double R4p[kN] = {}, r3p = 0, Pp[kPackedSize<kN>] = {}, vp[kN] = {};
  for (int t = 0; t < m; ++t) {
    ApplyStep(t, alpha, true);
    double vd[kN], R4[kN];
    const double* xt = x_ + t * kN;
    const double r3 = StepResidual(t, xt, t > 0 ? xt - kN : nullptr, vd, R4, &out);
    if (t > 0) {
      CompleteR4(t - 1, vd, R4p, &out);
      if (ok) ok = FactorStep(t - 1, R4p, r3p, t > 1, false, Pp, vp);
    }
    for (int i = 0; i < kN; ++i) R4p[i] = R4[i];
    r3p = r3;
  }
  const double* xm = x_ + m * kN;  // vd_m (x_m is stepped): R4_{m-1} complete
  double vd[kN], r[kN];
  ProcessDual(Constants(m), xm, xm - kN, r, vd);
  CompleteR4(m - 1, vd, R4p, &out);
  if (ok) ok = FactorStep(m - 1, R4p, r3p, m > 1, false, Pp, vp);
  *factored = ok;
  return out;
}

// Bottom half, t = T … m+1: step (x_{t-1} one step ahead, so that vd_t can be formed), residuals (R4_t is
// complete at step t, vd_{t+1} being known) and, one step behind as in the top half (a step's factorisation then
// overlaps the next step's residuals), the factorisation from the end. *vd_below: vd_{m+1}.
template <int kN>
IDENT_SIMD_CLONES inline typename FastSolver<kN>::Residuals FastSolver<kN>::BottomForward(double alpha,
                                                                                          double* vd_below,
                                                                                          bool* factored) {
  Residuals out;
  const int m = Middle();
  if (m == T_) return out;
  bool ok = true;  // on this thread's stack, as `out`
  double vdn[kN] = {}, R4n[kN] = {}, r3n = 0, Qn[kPackedSize<kN>] = {}, wn[kN] = {};  // vd, R4, R3 of step t+1
  if (alpha > 0)
    for (int i = 0; i < kN; ++i) x_[T_ * kN + i] += alpha * steps_[T_].dx[i];
  for (int t = T_; t > m; --t) {
    if (t - 1 > m && alpha > 0)
      for (int i = 0; i < kN; ++i) x_[(t - 1) * kN + i] += alpha * steps_[t - 1].dx[i];
    ApplyStep(t, alpha, false);
    double vd[kN], R4[kN];
    const double* xt = x_ + t * kN;
    const double r3 = StepResidual(t, xt, xt - kN, vd, R4, &out);
    if (t < T_) {
      CompleteR4(t, vdn, R4, &out);
      if (ok) ok = FactorStep(t + 1, R4n, r3n, false, t + 1 < T_, Qn, wn);
    } else {
      for (int i = 0; i < kN; ++i) out.r4max = std::max(out.r4max, std::abs(R4[i]));
    }
    for (int i = 0; i < kN; ++i) {
      vdn[i] = vd[i];
      R4n[i] = R4[i];
    }
    r3n = r3;
  }
  if (ok) ok = FactorStep(m + 1, R4n, r3n, false, m + 1 < T_, Qn, wn);
  for (int i = 0; i < kN; ++i) vd_below[i] = vdn[i];
  *factored = ok;
  return out;
}

// Step t of the factorisation fused with the predictor's forward substitution. With Pa = P_{t-1} (from_above: the
// top half eliminates into t) and Qb = Q_{t+1} (from_below), S0 = Db_t - E_t Pa E_t' - E_{t+1}' Qb E_{t+1}
// (SchurBase), P_t = (S0 + K^-1 H'H)^-1 (StepInverse) and v_t = P_t (b_t - E_t va - E_{t+1}' wb) =
// rt3 gf - P_t (R4_t + E_t va + E_{t+1}' wb) with b_t = -R4_t + H' K^-1 rt3, where P_t H' K^-1 rt3 = rt3 gf
// exactly (no product with the large K^-1), rt3 = R3 - e, e = S_hi^-1 (-R2_hi + Q_hi R1_hi) - S_lo^-1 (-R2_lo +
// Q_lo R1_lo) (the general path's RightHandSide; the predictor's R2 = s .* q). Pa, va, Qb, wb: the carried P and v
// (`carry`, `v_carry`, which receive P_t and v_t), else the neighbours' records. False if S0 is not numerically
// positive definite.
template <int kN>
[[gnu::always_inline]] inline bool FastSolver<kN>::FactorStep(int t, const double* R4, double r3, bool from_above,
                                                              bool from_below, double* carry, double* v_carry) {
  const StepConstants<kN>& c = Constants(t);
  StepState<kN>& s = steps_[t];
  const double* Pa = from_above ? (carry ? carry : steps_[t - 1].P) : nullptr;
  const double* va = from_above ? (v_carry ? v_carry : steps_[t - 1].v) : nullptr;
  const double* Qb = from_below ? (carry ? carry : steps_[t + 1].P) : nullptr;
  const double* wb = from_below ? (v_carry ? v_carry : steps_[t + 1].v) : nullptr;
  Reciprocals(s);
  const double islo = s.islo, ishi = s.ishi;
  const double ikd = c.m + s.qlo * islo + s.qhi * ishi;  // K = M + D, D = q/s (barrier curvature)
  const double kd = 1.0 / ikd;
  s.kd = kd;
  double S0[kN * kN], P[kN * kN], gf[kN];
  SchurBase<kN>(c, Pa, Qb, S0);
  if (!StepInverse<kN>(c, S0, ikd, kd, P, gf)) return false;
  const double u = s.u, slo = s.slo, shi = s.shi, qlo = s.qlo, qhi = s.qhi;
  const double r1hi = u + shi - c.hi, r1lo = -u + slo + c.lo;
  const double r2lo = slo * qlo, r2hi = shi * qhi;
  const double e = (-r2hi + qhi * r1hi) * ishi - (-r2lo + qlo * r1lo) * islo;
  const double rt3 = r3 - e;
  double Pk[kPackedSize<kN>];
  for (int k = 0; k < kN; ++k)
    for (int i = 0; i <= k; ++i) Pk[Packed(i, k)] = P[i + k * kN];
  double v[kN];
  SubstitutionStep<kN>(c, Pk, gf, rt3, R4, va, wb, v);
  for (int i = 0; i < kPackedSize<kN>; ++i) s.P[i] = Pk[i];
  for (int i = 0; i < kN; ++i) {
    s.gf[i] = gf[i];
    s.v[i] = v[i];
  }
  s.rt3 = rt3;
  if (carry)
    for (int i = 0; i < kPackedSize<kN>; ++i) carry[i] = Pk[i];
  if (v_carry)
    for (int i = 0; i < kN; ++i) v_carry[i] = v[i];
  return true;
}

// The corrector's right-hand side differs from the predictor's only in R2, by -target + ds_aff .* dq_aff:
// rt3 changes by d_t = (target - ds_lo dq_lo) / s_lo - (target - ds_hi dq_hi) / s_hi and, the substitutions being
// linear, v_t by dv_t = d_t gf_t - P_t (E_t dv_{t-1} + E_{t+1}' dw_{t+1}) (no products with R4_t), over each half
// and then the middle.
template <int kN>
inline void FastSolver<kN>::CorrectorForward(double target) {
  const int m = Middle();
  double dv_above[kN] = {}, dw_below[kN] = {};
  fork_.Run([&] { CorrectorHalf(target, 0, m, 1, dv_above); }, [&] { CorrectorHalf(target, T_, m, -1, dw_below); });
  CorrectorStep(target, m, m > 0 ? dv_above : nullptr, m < T_ ? dw_below : nullptr, nullptr);
}

// t = from, from + dir, … (not `to`); *last: the last step's dv.
template <int kN>
IDENT_SIMD_CLONES inline void FastSolver<kN>::CorrectorHalf(double target, int from, int to, int dir, double* last) {
  double dv[kN] = {};
  for (int t = from; t != to; t += dir) {
    const bool first = t == from;
    CorrectorStep(target, t, dir > 0 && !first ? dv : nullptr, dir < 0 && !first ? dv : nullptr, dv);
  }
  for (int i = 0; i < kN; ++i) last[i] = dv[i];
}

template <int kN>
[[gnu::always_inline]] inline void FastSolver<kN>::CorrectorStep(double target, int t, const double* dva,
                                                                 const double* dwb, double* dv_out) {
  const StepConstants<kN>& c = Constants(t);
  StepState<kN>& s = steps_[t];
  double dslo, dshi;
  SlackDirections(c, s, s.du, &dslo, &dshi);
  const double d = (target - dslo * s.dqlo) * s.islo - (target - dshi * s.dqhi) * s.ishi;
  double dv[kN];
  SubstitutionStep<kN>(c, s.P, s.gf, d, nullptr, dva, dwb, dv);
  for (int i = 0; i < kN; ++i) s.v[i] += dv[i];
  s.rt3 += d;
  if (dv_out)
    for (int i = 0; i < kN; ++i) dv_out[i] = dv[i];
}

// dx_m = v_m, then outwards: dx_t = v_t - P_t E_{t+1}' dx_{t+1} (top half), dx_t = w_t - Q_t E_t dx_{t-1}
// (bottom half), each fused with the recovery of du = K^-1 (rt3 - H dx), ds, dq (the general path's
// Direction), the largest step keeping s, q > 0 and the complementarity sums.
template <int kN>
inline typename FastSolver<kN>::Backward FastSolver<kN>::BackwardAndRecover(double target, bool corrector) {
  const int m = Middle();
  Backward middle, top, bottom;
  const double* dxm = steps_[m].v;
  Recover(m, dxm, target, corrector, &middle);
  fork_.Run([&] { BackwardHalf(target, corrector, m - 1, -1, &top); },
            [&] { BackwardHalf(target, corrector, m + 1, T_ + 1, &bottom); });
  Backward out;
  out.max_ratio = std::max({middle.max_ratio, top.max_ratio, bottom.max_ratio});
  out.sum1 = middle.sum1 + top.sum1 + bottom.sum1;
  out.sum2 = middle.sum2 + top.sum2 + bottom.sum2;
  if (out.max_ratio > 0) out.max_step = 1.0 / out.max_ratio;
  return out;
}

// t = from, … (not `to`), away from the middle step.
template <int kN>
IDENT_SIMD_CLONES inline void FastSolver<kN>::BackwardHalf(double target, bool corrector, int from, int to,
                                                           Backward* result) {
  Backward sums;  // on this thread's stack: the two halves' results would share a cache line
  Backward* const out = &sums;
  const int dir = to > from ? 1 : -1;
  double dxn[kN];  // dx of the previous step of this pass (nearer the middle)
  if (from != to)
    for (int i = 0; i < kN; ++i) dxn[i] = steps_[from - dir].dx[i];
  for (int t = from; t != to; t += dir) {
    StepState<kN>& s = steps_[t];
    // top: P_t E_{t+1}' dx_{t+1}; bottom: Q_t E_t dx_{t-1}
    const double* E = dir < 0 ? Constants(t + 1).E : Constants(t).E;
    double ex[kN];
    for (int i = 0; i < kN; ++i) {
      double e = 0;
      for (int k = 0; k < kN; ++k) e += (dir < 0 ? E[k + i * kN] : E[i + k * kN]) * dxn[k];
      ex[i] = e;
    }
    double dx[kN];
    for (int i = 0; i < kN; ++i) {
      double nd = s.P[Packed(i, 0)] * ex[0];
      for (int k = 1; k < kN; ++k) nd += s.P[Packed(i, k)] * ex[k];
      dx[i] = s.v[i] - nd;
    }
    Recover(t, dx, target, corrector, out);
    for (int i = 0; i < kN; ++i) dxn[i] = dx[i];
  }
  *result = sums;
}

template <int kN>
[[gnu::always_inline]] inline void FastSolver<kN>::Recover(int t, const double* dx, double target, bool corrector,
                                                           Backward* out) {
  const StepConstants<kN>& c = Constants(t);
  StepState<kN>& s = steps_[t];
  double hdx = 0;
  for (int i = 0; i < kN; ++i) {
    s.dx[i] = dx[i];
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
  out->max_ratio = std::max({out->max_ratio, -dslo * islo, -dshi * ishi});
  // -dq/q by a division only where it exceeds the largest ratio so far (rarely, after the first steps): the
  // records keep no 1/q, which the passes would stream from memory at large T.
  if (-dqlo > out->max_ratio * qlo) out->max_ratio = std::max(out->max_ratio, -dqlo / qlo);
  if (-dqhi > out->max_ratio * qhi) out->max_ratio = std::max(out->max_ratio, -dqhi / qhi);
  if (!corrector) {
    out->sum1 += slo * dqlo + qlo * dslo + shi * dqhi + qhi * dshi;
    out->sum2 += dslo * dqlo + dshi * dqhi;
  }
}

}  // namespace ident::internal::fast_path
