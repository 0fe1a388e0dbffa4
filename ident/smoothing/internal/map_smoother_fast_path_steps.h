// The per-step records and small kernels of the MAP smoother's fast path (internal to
// ident/smoothing/internal/map_smoother_fast_path.cc; see map_smoother_fast_path.h): the step constants and
// iterate, the constants' assembly, reciprocals, the slack directions, and the Schur complements and their inverses
// of the factorisation, which runs from both ends of the record and meets in the middle.
#pragma once

#include <cmath>
#include <limits>

#include <Eigen/Core>

#include "ident/smoothing/internal/small_kernels.h"
#include "ident/smoothing/map_smoother.h"

namespace ident::internal::fast_path {

// The data of one time step that does not change between iterations. Time-invariant problems share three
// of these (t = 0, 0 < t < T, t = T); time-varying ones have one per step.
template <int kN>
struct StepConstants {
  double Db[kN * kN];  // constant Newton block D_t = W_t + F_t' W_{t+1} F_t (process terms)
  double E[kN * kN];   // sub-diagonal block E_t = -W_t F_{t-1} (t >= 1)
  double En[kN * kN];  // E_{t+1} (t < T): the bottom-up half of the factorisation eliminates through it
  double F[kN * kN];   // F_{t-1} (t >= 1)
  double W[kN * kN];   // W_t = B'K^-1 B of the process penalty f_t (bound-free: u = K^-1 (B r - b) implicitly)
  double c0[kN];       // c0 = p - B'K^-1 b: p + B'u = c0 + W r
  double H[kN];        // H_t (1 x n)
  // n = 2: E_t P E_t' for a symmetric P as (E P E')_ij = EPE[3k] p11 + EPE[3k+1] p12 + EPE[3k+2] p22,
  // ij = 11, 12, 22 (k = 0, 1, 2): one level of products on the factorisation's recurrence; ETE the same for
  // E_{t+1}' Q E_{t+1}.
  double EPE[9], ETE[9];
  double lo, hi, m;  // measurement penalty: box [lo, hi], M = m
};

// A symmetric kN x kN matrix as its upper triangle, column by column: (i, k), i <= k, at i + k(k+1)/2. The step
// records and the passes' carried blocks keep P_t this way: at large T the passes stream the records from memory.
template <int kN>
constexpr int kPackedSize = kN*(kN + 1) / 2;
constexpr int Packed(int i, int k) { return i <= k ? i + k * (k + 1) / 2 : k + i * (i + 1) / 2; }

// The iterate and work values of one time step (nz = 1: one PLQ coordinate per step).
template <int kN>
struct StepState {
  double u, slo, shi, qlo, qhi;  // multiplier of g_t, slacks and multipliers of lo <= u <= hi
  double du, dqlo, dqhi;         // Newton direction (ds_lo, ds_hi follow from du: SlackDirections)
  double islo, ishi;             // 1/s_lo, 1/s_hi (once per iteration: no divisions in the other passes)
  double kd;                     // 1 / (m + q_lo/s_lo + q_hi/s_hi) = K^-1
  double rt3;                    // R3 - e of the current direction (R3 and R4 live only in the forward pass)
  double v[kN];                  // forward-substituted right-hand side, v_t = P_t (b_t - E_t v_{t-1})
  double dx[kN];                 // state direction
  double gf[kN];                 // P_t H' K^-1 (the measurement's rank-one term)
  // Top half (t < m): P_t = S_t^-1, v_t = P_t (b_t - E_t v_{t-1}), dx_t = v_t - P_t E_{t+1}' dx_{t+1}. Bottom half
  // (t > m): the same names for Q_t and w_t of the elimination from the end, w_t = Q_t (b_t - E_{t+1}' w_{t+1}),
  // dx_t = w_t - Q_t E_t dx_{t-1}. Middle (t = m): the inverse of the Schur complement of both, and v_m = dx_m.
  double P[kPackedSize<kN>];  // packed (Packed)
};

// 1/s_lo and 1/s_hi by one division, 1/(s_lo s_hi), when that product is a normal number (two divisions
// otherwise): the divider, not the arithmetic, bounds the factorisation pass.
template <int kN>
[[gnu::always_inline]] inline void Reciprocals(StepState<kN>& s) {
  const double ss = s.slo * s.shi;
  if (ss >= std::numeric_limits<double>::min() && ss <= std::numeric_limits<double>::max()) {
    const double inv = 1.0 / ss;
    s.islo = s.shi * inv;
    s.ishi = s.slo * inv;
  } else {
    s.islo = 1.0 / s.slo;
    s.ishi = 1.0 / s.shi;
  }
}

// The slack directions of the direction du at the iterate of s: ds_lo = -R1_lo + du, ds_hi = -R1_hi - du with
// R1_lo = -u + s_lo + lo and R1_hi = u + s_hi - hi (zero up to rounding: the iterate keeps C'u + s = c). Computed
// where they are used rather than stored: at large T the passes stream the step records from memory.
template <int kN>
[[gnu::always_inline]] inline void SlackDirections(const StepConstants<kN>& c, const StepState<kN>& s, double du,
                                                   double* dslo, double* dshi) {
  *dshi = -(s.u + s.shi - c.hi) - du;
  *dslo = -(-s.u + s.slo + c.lo) + du;
}

// The process residual r = x_t - F_{t-1} x_{t-1} (xp = x_{t-1}; nullptr at t = 0: r = x_0) and its dual value
// vd = c0 + W r (p + B'u of the bound-free process penalty).
template <int kN>
[[gnu::always_inline]] inline void ProcessDual(const StepConstants<kN>& c, const double* x, const double* xp, double* r,
                                               double* vd) {
  for (int i = 0; i < kN; ++i) r[i] = x[i];
  if (xp)
    for (int j = 0; j < kN; ++j)
      for (int i = 0; i < kN; ++i) r[i] -= c.F[i + j * kN] * xp[j];
  for (int i = 0; i < kN; ++i) vd[i] = c.c0[i];
  for (int j = 0; j < kN; ++j)
    for (int i = 0; i < kN; ++i) vd[i] += c.W[i + j * kN] * r[j];
}

// The step constants of step t: W = W_t and c0 = c0_t of the process penalty f_t (in the unit σ), W_next =
// W_{t+1} (nullptr at t = T), the measurement penalty's box and M divided by the data unit sigma.
template <int kN>
void FillStepConstants(const MapSmootherProblem& p, int t, const Eigen::MatrixXd& W_t, const Eigen::VectorXd& c0,
                       const Eigen::MatrixXd* W_next, double sigma, StepConstants<kN>* c) {
  using MatN = Eigen::Matrix<double, kN, kN>;
  using VecN = Eigen::Matrix<double, kN, 1>;
  const MatN W = W_t;
  MatN Db = W, E = MatN::Zero(), En = MatN::Zero(), F = MatN::Zero();
  if (W_next) {
    const MatN Fn = p.Ft(t);
    Db += Fn.transpose() * MatN(*W_next) * Fn;
    En = -MatN(*W_next) * Fn;
  }
  if (t > 0) {
    F = p.Ft(t - 1);
    E = -W * F;
  }
  Eigen::Map<MatN>(c->Db) = Db;
  Eigen::Map<MatN>(c->E) = E;
  Eigen::Map<MatN>(c->En) = En;
  Eigen::Map<MatN>(c->F) = F;
  Eigen::Map<MatN>(c->W) = W;
  Eigen::Map<VecN>(c->c0) = c0;
  Eigen::Map<VecN>(c->H) = p.Ht(t).row(0).transpose();
  if constexpr (kN == 2) {
    const int ij[3][2] = {{0, 0}, {0, 1}, {1, 1}};
    const MatN Et = En.transpose();
    for (int k = 0; k < 3; ++k) {
      const int i = ij[k][0], j = ij[k][1];
      c->EPE[3 * k] = E(i, 0) * E(j, 0);
      c->EPE[3 * k + 1] = E(i, 0) * E(j, 1) + E(i, 1) * E(j, 0);
      c->EPE[3 * k + 2] = E(i, 1) * E(j, 1);
      c->ETE[3 * k] = Et(i, 0) * Et(j, 0);
      c->ETE[3 * k + 1] = Et(i, 0) * Et(j, 1) + Et(i, 1) * Et(j, 0);
      c->ETE[3 * k + 2] = Et(i, 1) * Et(j, 1);
    }
  }
  const models::PlqForm& g = p.gt(t).plq();
  c->lo = g.lo(0) / sigma;  // in the unit σ
  c->hi = g.hi(0) / sigma;
  c->m = g.M(0, 0);
}

// S0 = Db_t - E_t Pa E_t' - E_{t+1}' Qb E_{t+1} (column-major, symmetric): the Schur complement of step t
// before the measurement's term, with Pa = P_{t-1} of the top half and Qb = Q_{t+1} of the bottom half (packed;
// each nullptr where that side does not eliminate into step t).
template <int kN>
[[gnu::always_inline]] inline void SchurBase(const StepConstants<kN>& c, const double* Pa, const double* Qb,
                                             double* S0) {
  if constexpr (kN == 2) {
    double s11 = c.Db[0], s12 = c.Db[1], s22 = c.Db[3];
    if (Pa) {
      const double p11 = Pa[0], p12 = Pa[1], p22 = Pa[2];
      s11 -= c.EPE[0] * p11 + c.EPE[1] * p12 + c.EPE[2] * p22;
      s12 -= c.EPE[3] * p11 + c.EPE[4] * p12 + c.EPE[5] * p22;
      s22 -= c.EPE[6] * p11 + c.EPE[7] * p12 + c.EPE[8] * p22;
    }
    if (Qb) {
      const double q11 = Qb[0], q12 = Qb[1], q22 = Qb[2];
      s11 -= c.ETE[0] * q11 + c.ETE[1] * q12 + c.ETE[2] * q22;
      s12 -= c.ETE[3] * q11 + c.ETE[4] * q12 + c.ETE[5] * q22;
      s22 -= c.ETE[6] * q11 + c.ETE[7] * q12 + c.ETE[8] * q22;
    }
    S0[0] = s11;
    S0[1] = S0[2] = s12;
    S0[3] = s22;
  } else {
    for (int i = 0; i < kN * kN; ++i) S0[i] = c.Db[i];
    // S0 -= A X A'' with A = E_t, X = Pa (transposed = false) or A = E_{t+1}', X = Qb.
    const auto subtract = [&](const double* X, const double* A, bool transposed) {
      const auto a = [&](int i, int k) { return transposed ? A[k + i * kN] : A[i + k * kN]; };
      double XA[kN * kN];  // X A'
      for (int j = 0; j < kN; ++j)
        for (int i = 0; i < kN; ++i) {
          double xa = 0;
          for (int k = 0; k < kN; ++k) xa += X[Packed(i, k)] * a(j, k);
          XA[i + j * kN] = xa;
        }
      for (int j = 0; j < kN; ++j)
        for (int i = 0; i < kN; ++i) {
          double axa = 0;
          for (int k = 0; k < kN; ++k) axa += a(i, k) * XA[k + j * kN];
          S0[i + j * kN] -= axa;
        }
    };
    if (Pa) subtract(Pa, c.E, false);
    if (Qb) subtract(Qb, c.En, true);
  }
}

// P = (S0 + K^-1 H'H)^-1 and gf = P H' K^-1 from S0 (SchurBase), ikd = K and kd = K^-1. K^-1 grows to ~1/mu on the
// coordinates at a kink, where inverting S0 + K^-1 H'H directly cancels terms of order K^-2 (tested: the
// iteration then stalls near 1e-10). The measurement's rank-one term enters the inverse with the factor K instead:
//   n = 2: P = (K adj(S0) + adj(H'H)) / (K det(S0) + H adj(S0) H')   (adj is linear for 2 x 2,
//          det(S0 + k h h') = det(S0) + k h'adj(S0)h), one division, no differences of large terms;
//   else:  Sherman-Morrison, P = P0 - g g' / (K + H g), P0 = S0^-1, g = P0 H'.
// False if S0 is not numerically positive definite.
template <int kN>
[[gnu::always_inline]] inline bool StepInverse(const StepConstants<kN>& c, double* S0, double ikd, double kd, double* P,
                                               double* gf) {
  if constexpr (kN == 2) {
    const double s11 = S0[0], s12 = S0[1], s22 = S0[3];
    const double det = s11 * s22 - s12 * s12;
    if (!(s11 > 0) || !(det > 0) || !std::isfinite(det)) return false;
    const double h1 = c.H[0], h2 = c.H[1];
    const double a1 = s22 * h1 - s12 * h2, a2 = s11 * h2 - s12 * h1;  // adj(S0) H'
    double id = 1.0 / (ikd * det + (h1 * a1 + h2 * a2)), bid = id;
    double a = ikd, b = 1;
    if (!(ikd <= 1e150)) {  // K S0 could overflow: numerator and denominator divided by K
      a = 1;
      b = kd;
      id = 1.0 / (det + kd * (h1 * a1 + h2 * a2));
      bid = kd * id;
    }
    P[0] = (a * s22 + b * (h2 * h2)) * id;
    P[1] = P[2] = -(a * s12 + b * (h1 * h2)) * id;
    P[3] = (a * s11 + b * (h1 * h1)) * id;
    gf[0] = a1 * bid;  // P H' K^-1 = adj(S0) H' / (K det(S0) + H adj(S0) H')
    gf[1] = a2 * bid;
  } else {
    for (int i = 0; i < kN * kN; ++i) P[i] = S0[i];
    if (!InvertSpd<kN>(P)) return false;
    double g[kN], hg = 0;
    for (int i = 0; i < kN; ++i) {
      double gi = 0;
      for (int k = 0; k < kN; ++k) gi += P[i + k * kN] * c.H[k];
      g[i] = gi;
      hg += c.H[i] * gi;
    }
    const double f = 1.0 / (ikd + hg);
    for (int j = 0; j < kN; ++j)
      for (int i = 0; i < kN; ++i) P[i + j * kN] -= f * g[i] * g[j];
    for (int i = 0; i < kN; ++i) gf[i] = f * g[i];
  }
  return true;
}

// One step of the forward substitutions: v = a gf - P (b + E_t va + E_{t+1}' wb), P packed, with va = v_{t-1} of the
// top half and wb = w_{t+1} of the bottom half (each nullptr where that side does not eliminate into step t; b
// nullptr: 0).
template <int kN>
[[gnu::always_inline]] inline void SubstitutionStep(const StepConstants<kN>& c, const double* P, const double* gf,
                                                    double a, const double* b, const double* va, const double* wb,
                                                    double* v) {
  double w[kN];
  for (int i = 0; i < kN; ++i) w[i] = b ? b[i] : 0.0;
  if (va)
    for (int k = 0; k < kN; ++k)
      for (int i = 0; i < kN; ++i) w[i] += c.E[i + k * kN] * va[k];
  if (wb)
    for (int i = 0; i < kN; ++i)
      for (int k = 0; k < kN; ++k) w[i] += c.En[k + i * kN] * wb[k];
  for (int i = 0; i < kN; ++i) {
    double pw = P[Packed(i, 0)] * w[0];  // the sums start at their first term: no + 0.0 (which does not fold)
    for (int k = 1; k < kN; ++k) pw += P[Packed(i, k)] * w[k];
    v[i] = a * gf[i] - pw;
  }
}

}  // namespace ident::internal::fast_path
