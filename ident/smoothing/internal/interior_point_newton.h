// The Newton system and the step of the MAP smoother's interior-point iteration (internal to
// ident/smoothing/internal/interior_point.cc; the class in interior_point_solver.h): the residuals R3, R4,
// the block-tridiagonal Newton matrix, the Newton direction [ABP eq. (4.3)] and the step.
#pragma once

#include <algorithm>
#include <limits>

#include <Eigen/Core>

#include "ident/linalg/block_tridiagonal.h"
#include "ident/smoothing/internal/interior_point_solver.h"
#include "ident/smoothing/internal/small_kernels.h"

namespace ident::internal::interior_point {

// R3 = B r - b - M u - (q_hi - q_lo) per term, R4 = sum J'(p + B'u); returns the scale of p + B'u.
template <int kN>
inline double Solver<kN>::Residuals() {
  R4_.setZero();
  objective_scale_ = 0;
  double v_scale = 1;
  double* r = r_.data();
  double* v = v_.data();
  for (const Term& term : terms_) {
    const Prepared& prep = *term.prep;
    const PlqForm& f = *prep.plq;
    const int m = prep.m, k = prep.k;
    Residual(term, x_.data(), true, r);
    if (prep.constant) {  // u = K^-1 (B r - b): p + B'u = c0 + W r, R3 = 0
      const double* W = prep.W.data();
      if (term.process && prep.identity_B) {  // m = n, c0 = 0
        for (int i = 0; i < m; ++i) v[i] = 0;
        AddMatVec<kN, kN>(W, m, m, r, v, 1.0);
      } else {
        for (int i = 0; i < m; ++i) v[i] = prep.c0(i);
        AddMatVec(W, m, m, r, v, 1.0);
      }
      for (int i = 0; i < m; ++i) {
        v_scale = std::max(v_scale, std::abs(v[i]));
        objective_scale_ += std::abs(v[i] * r[i]);
      }
      AddJt(term, v, 1.0, R4_.data());
      continue;
    }
    const double* u = u_.data() + term.offset;
    double* r3 = r3_.data() + term.offset;
    if (prep.identity_B) {
      for (int i = 0; i < m; ++i) v[i] = u[i];
      for (int i = 0; i < k; ++i) r3[i] = r[i];
    } else {
      for (int i = 0; i < m; ++i) v[i] = f.p(i);
      AddMatTVec(f.B.data(), k, m, u, v, 1.0);
      for (int i = 0; i < k; ++i) r3[i] = -f.b(i);
      AddMatVec(f.B.data(), k, m, r, r3, 1.0);
    }
    for (int i = 0; i < m; ++i) {
      v_scale = std::max(v_scale, std::abs(v[i]));
      objective_scale_ += std::abs(f.p(i) * r[i]);
    }
    for (int i = 0; i < k; ++i) objective_scale_ += std::abs(u[i] * r3[i]);  // u'(B r - b)
    AddJt(term, v, 1.0, R4_.data());
    if (f.diagonal_M) {
      const double* M = f.M.data();
      for (int i = 0; i < k; ++i) r3[i] -= M[i + i * k] * u[i];
    } else {
      AddMatVec(f.M.data(), k, k, u, r3, -1.0);
    }
    for (int i = 0; i < k; ++i) r3[i] -= qhi_(term.offset + i) - qlo_(term.offset + i);
  }
  return v_scale;
}

// The multipliers of the one-sided bounds (the domain indicators of a piecewise-linear penalty, u ≥ 0)
// at the start, chosen so that their stationarity residual vanishes: q = max(1, ∓e) with
// e = B r − b − M u at the initial states. With a unit multiplier a domain bound far from the residual
// (1000 away) starts with |R3| ≈ 1000 ≫ the complementarity, and the iteration drives the multiplier to
// infinity instead of the residual to its value ("infeasible"). Two-sided boxes keep the unit start.
template <int kN>
inline void Solver<kN>::BalanceOneSidedMultipliers() {
  Residuals();
  for (int c : bounded_) {
    if (has_lo_[c] == has_hi_[c]) continue;
    const double e = r3_(c) + (qhi_(c) - qlo_(c));  // the stationarity residual without the multipliers
    if (has_lo_[c])
      qlo_(c) = std::max(1.0, -e);
    else
      qhi_(c) = std::max(1.0, e);
  }
}

// sum (s + a ds) .* (q + a dq) over finite bounds.
template <int kN>
inline double Solver<kN>::Complementarity(double a) const {
  double sum = 0;
  for (int c : bounded_) {
    if (has_lo_[c]) sum += (slo_(c) + a * dslo_(c)) * (qlo_(c) + a * dqlo_(c));
    if (has_hi_[c]) sum += (shi_(c) + a * dshi_(c)) * (qhi_(c) + a * dqhi_(c));
  }
  return sum;
}

template <int kN>
inline void Solver<kN>::FactorK(const Term& term) {
  Prepared& prep = *term.prep;
  prep.K = prep.plq->M;
  prep.K.diagonal() += kd_.segment(term.offset, prep.k);
  prep.llt.compute(prep.K);
}

// D_t, E_t += J' W J for one term (W: m x m, column-major).
template <int kN>
inline void Solver<kN>::AddNewtonBlocks(const Term& term, const double* W, double* D, double* E) {
  const int n = this->n(), t = term.t;
  const Eigen::Index nn = static_cast<Eigen::Index>(n) * n;
  double* Dt = D + t * nn;
  double* WF = WF_.data();
  if (term.process) {
    for (int i = 0; i < n * n; ++i) Dt[i] += W[i];
    if (term.F) AddProcessCoupling(W, term.F, n, WF, E + t * nn, Dt - nn);  // D_{t-1} += F'WF, E_t -= W F
  } else {
    AddMeasurementBlock(W, term.H, n, nz_, WF, Dt);  // D_t += H'WH
  }
}

// D_, E_ = sum_terms J' B' K^-1 B J   (block tridiagonal): the precomputed constant part plus the
// terms with bounds, whose K = M + diag(q_hi/s_hi + q_lo/s_lo) changes every iteration.
template <int kN>
inline void Solver<kN>::AssembleNewtonMatrix() {
  D_ = base_D_;
  if (e_changes_) E_ = base_E_;
  double* W = W_.data();
  for (const Term& term : active_) {
    Prepared& prep = *term.prep;
    const PlqForm& f = *prep.plq;
    const int m = prep.m, k = prep.k;
    double* kd = kd_.data() + term.offset;
    if (f.diagonal_M) {
      // diagonal M: kd holds the reciprocal diagonal of K = M + D (ApplyKinv multiplies)
      for (int i = 0; i < k; ++i) kd[i] = 1.0 / (BarrierCurvature(term.offset + i) + f.M(i, i));
      for (int i = 0; i < m * m; ++i) W[i] = 0;
      if (prep.identity_B) {
        for (int i = 0; i < k; ++i) W[i + i * m] = kd[i];
      } else {
        for (int i = 0; i < k; ++i) {
          const double inv = kd[i];
          for (int b = 0; b < m; ++b)
            for (int a = 0; a < m; ++a) W[a + b * m] += f.B(i, a) * f.B(i, b) * inv;
        }
      }
    } else {
      for (int i = 0; i < k; ++i) kd[i] = BarrierCurvature(term.offset + i);
      FactorK(term);
      prep.KinvB = prep.llt.solve(f.B);
      Eigen::Map<Eigen::MatrixXd>(W, m, m).noalias() = f.B.transpose() * prep.KinvB;
    }
    AddNewtonBlocks(term, W, D_.data(), E_.data());
  }
}

// Newton direction for F_mu = 0 [ABP eq. (4.3)], with slack s and multiplier q eliminated per term:
//   (M + D) du = B J dx + R3 - e,   e = S_hi^-1 (-R2_hi + Q_hi R1_hi) - S_lo^-1 (-R2_lo + Q_lo R1_lo)
//   sum J'B'K^-1 B J dx = -R4 - sum J'B'K^-1 (R3 - e)
// R1 (the linear box residual u + s - hi, -u + s - (-lo)) is kept in the formulas.
// Constant terms (no bounds) contribute nothing beyond R4: their R3 - e is 0 (u = K^-1 (B r - b)).
template <int kN>
inline void Solver<kN>::Direction(double target, bool corrector) {
  dx_ = -R4_;
  double* kinv = tk2_.data();
  double* g = g_.data();
  for (const Term& term : active_) {
    const Prepared& prep = *term.prep;
    const int k = prep.k, m = prep.m;
    double* rt3 = rt3_.data() + term.offset;
    RightHandSide(term, target, corrector, rt3);
    ApplyKinv(term, rt3, kinv);
    if (prep.identity_B) {
      AddJt(term, kinv, -1.0, dx_.data());
    } else {
      for (int i = 0; i < m; ++i) g[i] = 0;
      AddMatTVec(prep.plq->B.data(), k, m, kinv, g, 1.0);
      AddJt(term, g, -1.0, dx_.data());
    }
  }
  SolveBlockTridiagonal(n_, T_ + 1, C_.data(), G_.data(), dx_.data());
  double* rhs = tk_.data();
  double* r = r_.data();
  for (const Term& term : active_) {
    const Prepared& prep = *term.prep;
    const int k = prep.k, m = prep.m;
    const double* rt3 = rt3_.data() + term.offset;
    for (int i = 0; i < k; ++i) rhs[i] = rt3[i];
    Residual(term, dx_.data(), false, r);  // J dx
    if (prep.identity_B) {
      for (int i = 0; i < k; ++i) rhs[i] += r[i];
    } else {
      AddMatVec(prep.plq->B.data(), k, m, r, rhs, 1.0);
    }
    ApplyKinv(term, rhs, du_.data() + term.offset);
    for (int i = 0; i < k; ++i) {
      const int c = term.offset + i;
      double r2lo, r2hi;
      R2(c, target, corrector, &r2lo, &r2hi);
      if (has_hi_[c]) {
        const double r1 = u_(c) + shi_(c) - hi_(c);
        dshi_(c) = -r1 - du_(c);
        dqhi_(c) = (-r2hi - qhi_(c) * dshi_(c)) / shi_(c);
      }
      if (has_lo_[c]) {
        const double r1 = -u_(c) + slo_(c) + lo_(c);
        dslo_(c) = -r1 + du_(c);
        dqlo_(c) = (-r2lo - qlo_(c) * dslo_(c)) / slo_(c);
      }
    }
  }
}

// Largest a keeping s + a ds >= 0 and q + a dq >= 0 (+inf if no component decreases).
template <int kN>
inline double Solver<kN>::MaxStep() const {
  double a = std::numeric_limits<double>::infinity();
  auto limit = [&a](double value, double delta) {
    if (delta < 0) a = std::min(a, -value / delta);
  };
  for (int c : bounded_) {
    if (has_lo_[c]) {
      limit(slo_(c), dslo_(c));
      limit(qlo_(c), dqlo_(c));
    }
    if (has_hi_[c]) {
      limit(shi_(c), dshi_(c));
      limit(qhi_(c), dqhi_(c));
    }
  }
  return a;
}

template <int kN>
inline void Solver<kN>::Step(double a) {
  x_ += a * dx_;
  u_ += a * du_;
  for (int c : bounded_) {
    slo_(c) += a * dslo_(c);
    qlo_(c) += a * dqlo_(c);
    shi_(c) += a * dshi_(c);
    qhi_(c) += a * dqhi_(c);
  }
}

}  // namespace ident::internal::interior_point
