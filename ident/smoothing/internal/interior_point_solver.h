// The interior-point iteration of the MAP smoother's general path (internal to
// ident/smoothing/internal/interior_point.cc; see interior_point.h): its state, start point and per-term
// kernels. The iteration's steps are defined in interior_point.cc, the Newton system and the step in
// interior_point_newton.h.
#pragma once

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <new>
#include <vector>

#include <Eigen/Core>

#include "ident/linalg/work_arena.h"
#include "ident/smoothing/internal/interior_point_terms.h"
#include "ident/smoothing/internal/map_smoother_result.h"
#include "ident/smoothing/internal/small_kernels.h"
#include "ident/smoothing/map_smoother.h"

namespace ident::internal::interior_point {

// The interior-point iteration. kN > 0 fixes the state dimension n at compile time (n = 1..4: the
// per-step loops unroll); kN = 0 is the run-time-size fallback. All work arrays are allocated by the
// constructor; an iteration allocates nothing (except the dense K of non-diagonal box monitoring
// functions, which Eigen's LLT factors in place).
// Terms without finite bounds ("constant": quadratic penalties) carry no multipliers: their R3 = B r - b - M u
// is linear and stays 0 from a start with R3 = 0, so u = K^-1 (B r - b) is kept implicitly and only the
// terms with bounds (active_) have coordinate arrays and enter the Newton right-hand sides. The work arrays
// share one WorkArena block (huge pages for large T:
// ident/linalg/work_arena.h).
template <int kN>
class Solver {
 public:
  Solver(const MapSmootherProblem& p, const MapSmootherOptions& o)
      : p_(p),
        o_(o),
        T_(p.T()),
        n_(p.state_dim()),
        nz_(p.measurement_dim()),
        sigma_(MapSmootherDataUnit(p)),
        z_(p.z / sigma_) {
    int offset = 0;
    terms_.reserve(2 * (T_ + 1));
    for (int pass = 0; pass < 2; ++pass)
      for (int t = 0; t <= T_; ++t) {
        const Penalty& pen = pass == 0 ? p.ft(t) : p.gt(t);
        auto it = prepared_.find(&pen);
        if (it == prepared_.end()) it = prepared_.emplace(&pen, PreparePenalty(pen, sigma_)).first;
        const double* F = pass == 0 && t > 0 ? p.Ft(t - 1).data() : nullptr;
        const double* H = pass == 1 ? p.Ht(t).data() : nullptr;
        const bool constant = it->second->constant;
        terms_.push_back({it->second.get(), constant ? -1 : offset, t, pass == 0, F, H});
        if (!constant) {
          active_.push_back(terms_.back());
          offset += it->second->k;
          e_changes_ = e_changes_ || F != nullptr;
        }
      }
    // Work arrays, all in one block (ident/linalg/work_arena.h): coordinate arrays only for the terms with a
    // finite bound; constant terms keep u = K^-1 (B r - b) implicitly (R3 = 0 for them at every iterate,
    // so their Newton contribution is the precomputed J'WJ and the gradient J'(c0 + W r)).
    const std::size_t K = offset, N = T_ + 1, nN = static_cast<std::size_t>(n_) * N, blocks = nN * n_;
    using A = WorkArena;
    const std::size_t size =
        17 * A::Padded(K) + 3 * A::Padded(nN) + (4 + (e_changes_ ? 2 : 1)) * A::Padded(blocks) + A::Padded(n_);
    arena_ = std::make_unique<WorkArena>(size);
    for (Eigen::Map<Eigen::VectorXd>* v : {&u_, &slo_, &qlo_, &shi_, &qhi_, &lo_, &hi_, &r3_, &rt3_, &du_, &dslo_,
                                           &dqlo_, &dshi_, &dqhi_, &xlo_, &xhi_, &kd_})
      new (v) Eigen::Map<Eigen::VectorXd>(arena_->Take(K), static_cast<Eigen::Index>(K));
    for (Eigen::Map<Eigen::MatrixXd>* v : {&x_, &R4_, &dx_})
      new (v) Eigen::Map<Eigen::MatrixXd>(arena_->Take(nN), n_, static_cast<Eigen::Index>(N));
    for (Eigen::Map<Eigen::MatrixXd>* v : {&D_, &base_D_, &base_E_, &C_, &G_})
      new (v) Eigen::Map<Eigen::MatrixXd>(arena_->Take(blocks), n_, static_cast<Eigen::Index>(nN));
    // E changes between iterations only through bounded process terms; otherwise it is the constant part.
    new (&E_) Eigen::Map<Eigen::MatrixXd>(e_changes_ ? arena_->Take(blocks) : base_E_.data(), n_,
                                          static_cast<Eigen::Index>(nN));
    chol_work_ = arena_->Take(n_);
    StartPoint(K);
    for (const auto& F : p.F) matrix_scale_ = std::max(matrix_scale_, 1 + F.cwiseAbs().maxCoeff());
    for (const auto& H : p.H) matrix_scale_ = std::max(matrix_scale_, 1 + H.cwiseAbs().maxCoeff());
    for (auto& [_, prep] : prepared_)
      if (prep->constant) constant_weight_scale_ = std::max(constant_weight_scale_, prep->W.cwiseAbs().maxCoeff());
    const int m = std::max(n_, nz_);
    r_.resize(m);
    v_.resize(m);
    g_.resize(m);
    W_.resize(m * m);
    WF_.resize(m * n_);
    int kmax = 1;
    for (auto& [_, prep] : prepared_) kmax = std::max(kmax, prep->k);
    tk_.resize(kmax);
    tk2_.resize(kmax);
    // The Newton blocks of penalties without bounds do not change: add them up once.
    for (const Term& term : terms_)
      if (term.prep->constant) AddNewtonBlocks(term, term.prep->W.data(), base_D_.data(), base_E_.data());
  }

  MapSmootherResult Run();

 private:
  // The bounds per coordinate and a strictly interior start u, s, q for the K coordinates of the terms with
  // a finite bound.
  void StartPoint(std::size_t K) {
    has_lo_.assign(K, 0);
    has_hi_.assign(K, 0);
    for (const Term& term : active_) {
      const PlqForm& f = *term.prep->plq;
      for (int i = 0; i < f.rows(); ++i) {
        const int c = term.offset + i;
        lo_(c) = f.lo(i);
        hi_(c) = f.hi(i);
        has_lo_[c] = std::isfinite(lo_(c));
        has_hi_[c] = std::isfinite(hi_(c));
        const bool has_lo = has_lo_[c], has_hi = has_hi_[c];
        // A strictly interior start, so that C'u + s = c holds exactly from the first iterate.
        u_(c) = has_lo && has_hi ? 0.5 * (lo_(c) + hi_(c)) : has_lo ? lo_(c) + 1 : has_hi ? hi_(c) - 1 : 0.0;
        slo_(c) = has_lo ? u_(c) - lo_(c) : 1.0;
        shi_(c) = has_hi ? hi_(c) - u_(c) : 1.0;
        qlo_(c) = has_lo ? 1.0 : 0.0;
        qhi_(c) = has_hi ? 1.0 : 0.0;
        num_constraints_ += has_lo + has_hi;
        if (has_lo || has_hi) bounded_.push_back(c);
      }
    }
  }

  // The iteration's steps (interior_point.cc).
  double BoundScale() const;
  double KktResidual(double v_scale, double z_scale, double bound_scale, double mu, double* r4_floor_out,
                     double* x_scale_out) const;
  bool Stops(int iter, double kkt, const std::vector<double>& history, double relative_floor, double x_scale,
             double bound_scale, double z_scale, MapSmootherResult* res) const;
  void NewtonStep(double mu);
  void TermWeight(const Term& term, double* W);
  void TermDual(const Term& term, double* out);
  void Finish(MapSmootherResult* res, double z_scale, double mu);

  // The Newton system and the step (interior_point_newton.h).
  double Residuals();
  void BalanceOneSidedMultipliers();
  double Complementarity(double a) const;
  void FactorK(const Term& term);
  void AddNewtonBlocks(const Term& term, const double* W, double* D, double* E);
  void AssembleNewtonMatrix();
  void Direction(double target, bool corrector);
  double MaxStep() const;
  void Step(double a);

  int n() const { return kN > 0 ? kN : n_; }

  // r = residual of the term at x (process: x_t - F x_{t-1}; measurement: z_t - H_t x_t), or its
  // linear part J x (include_constant = false).
  [[gnu::always_inline]] inline void Residual(const Term& term, const double* x, bool include_constant,
                                              double* out) const {
    const int n = this->n(), t = term.t;
    const double* xt = x + static_cast<Eigen::Index>(t) * n;
    if (term.process) {
      for (int i = 0; i < n; ++i) out[i] = xt[i];
      if (term.F) AddMatVec<kN, kN>(term.F, n, n, xt - n, out, -1.0);
    } else {
      const double* zt = z_.data() + static_cast<Eigen::Index>(t) * nz_;
      for (int i = 0; i < nz_; ++i) out[i] = include_constant ? zt[i] : 0.0;
      AddMatVec<0, kN>(term.H, nz_, n, xt, out, -1.0);
    }
  }

  // out += sign * J' g
  [[gnu::always_inline]] inline void AddJt(const Term& term, const double* g, double sign, double* out) const {
    const int n = this->n();
    double* ot = out + static_cast<Eigen::Index>(term.t) * n;
    if (term.process) {
      for (int i = 0; i < n; ++i) ot[i] += sign * g[i];
      if (term.F) AddMatTVec<kN, kN>(term.F, n, n, g, ot - n, -sign);
    } else {
      AddMatTVec<0, kN>(term.H, nz_, n, g, ot, -sign);
    }
  }

  // D = q_hi/s_hi + q_lo/s_lo per coordinate (the barrier curvature C S^-1 Q C').
  [[gnu::always_inline]] inline double BarrierCurvature(int c) const {
    double d = 0;
    if (has_lo_[c]) d += qlo_(c) / slo_(c);
    if (has_hi_[c]) d += qhi_(c) / shi_(c);
    return d;
  }

  // out = K^-1 in for the term (K = M + diag(D)); dense factor computed by AssembleNewtonMatrix.
  [[gnu::always_inline]] inline void ApplyKinv(const Term& term, const double* in, double* out) {
    Prepared& prep = *term.prep;
    const int k = prep.k;
    if (prep.constant) {
      for (int i = 0; i < k; ++i) out[i] = 0;
      if (term.process && prep.identity_B)  // k = n
        AddMatVec<kN, kN>(prep.Kinv.data(), k, k, in, out, 1.0);
      else
        AddMatVec(prep.Kinv.data(), k, k, in, out, 1.0);
    } else if (prep.plq->diagonal_M) {
      const double* kd = kd_.data() + term.offset;
      for (int i = 0; i < k; ++i) out[i] = in[i] * kd[i];  // kd = 1 / (M_ii + D_ii) here
    } else {
      FactorK(term);
      Eigen::Map<Eigen::VectorXd>(out, k) = prep.llt.solve(Eigen::Map<const Eigen::VectorXd>(in, k));
    }
  }

  // Complementarity residuals R2 = s.*q (+ ds_aff.*dq_aff) - target for coordinate c.
  [[gnu::always_inline]] inline void R2(int c, double target, bool corrector, double* r2lo, double* r2hi) const {
    *r2lo = has_lo_[c] ? slo_(c) * qlo_(c) + (corrector ? xlo_(c) : 0.0) - target : 0.0;
    *r2hi = has_hi_[c] ? shi_(c) * qhi_(c) + (corrector ? xhi_(c) : 0.0) - target : 0.0;
  }

  [[gnu::always_inline]] inline void RightHandSide(const Term& term, double target, bool corrector, double* rt3) const {
    const int k = term.prep->k;
    if (term.prep->constant) {  // no bounds: e = 0
      for (int i = 0; i < k; ++i) rt3[i] = r3_(term.offset + i);
      return;
    }
    for (int i = 0; i < k; ++i) {
      const int c = term.offset + i;
      double r2lo, r2hi;
      R2(c, target, corrector, &r2lo, &r2hi);
      double e = 0;
      if (has_hi_[c]) e += (-r2hi + qhi_(c) * (u_(c) + shi_(c) - hi_(c))) / shi_(c);
      if (has_lo_[c]) e -= (-r2lo + qlo_(c) * (-u_(c) + slo_(c) + lo_(c))) / slo_(c);
      rt3[i] = r3_(c) - e;
    }
  }

  const MapSmootherProblem& p_;
  const MapSmootherOptions& o_;
  const int T_, n_, nz_;
  const double sigma_;       // the data unit (MapSmootherDataUnit)
  const Eigen::MatrixXd z_;  // the measurements in that unit
  std::map<const Penalty*, std::unique_ptr<Prepared>> prepared_;
  std::vector<Term> terms_;   // process terms t = 0..T, then measurement terms t = 0..T
  std::vector<Term> active_;  // the terms with a finite bound (non-constant Newton blocks), same order
  bool e_changes_ = false;    // an active process term couples x_{t-1}, x_t: E must be reassembled
  std::unique_ptr<WorkArena> arena_;
  int num_constraints_ = 0;
  double matrix_scale_ = 1;
  double constant_weight_scale_ = 0;  // max |W| of the bound-free terms (R4's round-off floor)
  double objective_scale_ = 0;        // sum over terms of |v'r| (dual value times residual): the objective's size
  // Per PLQ coordinate: u, slacks and multipliers of lo <= u <= hi, residual R3, R3 - e of the current
  // direction, Newton direction, affine cross terms ds.*dq, and K's diagonal (its reciprocal for
  // diagonal M).
  std::vector<char> has_lo_, has_hi_;  // finite bounds per coordinate
  std::vector<int> bounded_;           // coordinates with at least one finite bound
  // All of these live in arena_ (placement-constructed maps).
  using VectorMap = Eigen::Map<Eigen::VectorXd>;
  using MatrixMap = Eigen::Map<Eigen::MatrixXd>;
  VectorMap u_{nullptr, 0}, slo_{nullptr, 0}, qlo_{nullptr, 0}, shi_{nullptr, 0}, qhi_{nullptr, 0}, lo_{nullptr, 0},
      hi_{nullptr, 0}, r3_{nullptr, 0}, rt3_{nullptr, 0}, du_{nullptr, 0}, dslo_{nullptr, 0}, dqlo_{nullptr, 0},
      dshi_{nullptr, 0}, dqhi_{nullptr, 0}, xlo_{nullptr, 0}, xhi_{nullptr, 0}, kd_{nullptr, 0};
  // States, gradient R4 and direction (n x (T+1)); Newton blocks D, E, their constant parts and the
  // block Cholesky factor C, G (n x n(T+1)).
  MatrixMap x_{nullptr, 0, 0}, R4_{nullptr, 0, 0}, dx_{nullptr, 0, 0}, D_{nullptr, 0, 0}, E_{nullptr, 0, 0},
      base_D_{nullptr, 0, 0}, base_E_{nullptr, 0, 0}, C_{nullptr, 0, 0}, G_{nullptr, 0, 0};
  double* chol_work_ = nullptr;
  Eigen::VectorXd r_, v_, g_, tk_, tk2_, W_, WF_;
};

}  // namespace ident::internal::interior_point
