#include "ident/smoothing/internal/interior_point.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <new>
#include <vector>

#include <Eigen/Cholesky>

#include <fmt/format.h>

#include "common/error.h"
#include "ident/linalg/block_tridiagonal.h"
#include "ident/linalg/work_arena.h"
#include "ident/smoothing/internal/map_smoother_result.h"
#include "ident/smoothing/internal/small_kernels.h"

namespace ident::internal {
namespace {

using models::Penalty;
using models::PlqForm;

// Solver-side data of one distinct penalty.
struct Prepared {
  PlqForm scaled;                // the penalty's PLQ form in the data unit σ: p, b, lo, hi divided by σ
  const PlqForm* plq = nullptr;  // = &scaled
  int k = 0, m = 0;
  bool constant = false;    // no finite bound: K = M, W = B'M^-1 B fixed (its Newton block is precomputed)
  bool identity_B = false;  // B = I, b = 0, p = 0: v = p + B'u = u and B r - b = r
  Eigen::MatrixXd Kinv;     // constant case
  Eigen::MatrixXd W;        // constant case
  Eigen::VectorXd c0;       // constant case: at u = K^-1 (B r - b), p + B'u = c0 + W r with c0 = p - B'K^-1 b
  Eigen::MatrixXd K;        // dense case work
  Eigen::LLT<Eigen::MatrixXd> llt;
  Eigen::MatrixXd KinvB;  // dense case work (k x m)
};

struct Term {
  Prepared* prep;
  int offset;  // into the coordinate arrays (terms with a finite bound only; -1 for constant terms)
  int t;
  bool process;
  const double* F;  // F_{t-1} (process terms with t > 0), column-major n x n; else nullptr
  const double* H;  // H_t (measurement terms), column-major nz x n
};

#define IDENT_HOT [[gnu::always_inline]] inline

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
        if (it == prepared_.end()) it = prepared_.emplace(&pen, Prepare(pen, sigma_)).first;
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

  MapSmootherResult Run() {
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

 private:
  // The largest finite bound of the penalties' multipliers (at least 1).
  double BoundScale() const {
    double bound_scale = 1;
    for (int c : bounded_) {
      if (has_lo_[c]) bound_scale = std::max(bound_scale, std::abs(lo_(c)));
      if (has_hi_[c]) bound_scale = std::max(bound_scale, std::abs(hi_(c)));
    }
    return bound_scale;
  }

  // The relative KKT residual of the iterate after Residuals() (v_scale: its scale of p + B'u); also R4's
  // round-off floor and the states' size.
  double KktResidual(double v_scale, double z_scale, double bound_scale, double mu, double* r4_floor_out,
                     double* x_scale_out) const {
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
  bool Stops(int iter, double kkt, const std::vector<double>& history, double relative_floor, double x_scale,
             double bound_scale, double z_scale, MapSmootherResult* res) const {
    if (kkt <= o_.tolerance) {
      res->status = MapSmootherStatus::kConverged;
      return true;
    }
    if (iter >= o_.max_iterations) return true;
    if (iter >= kStallWindow && kkt > kStallProgress * history[iter - kStallWindow]) {
      res->status = MapSmootherStatus::kStalled;
      res->message = fmt::format(
          "stalled after {} iterations at KKT residual {:.1e} (no progress in the last {}; the residuals' "
          "round-off floor is {:.1e} for states of size {:.1e})",
          iter, kkt, kStallWindow, relative_floor, sigma_ * x_scale);
      return true;
    }
    if (u_.size() && u_.cwiseAbs().maxCoeff() > 1e10 * bound_scale * z_scale) {
      Eigen::Index c = 0;
      const double umax = u_.cwiseAbs().maxCoeff(&c);
      int t = -1;
      for (const Term& term : active_)
        if (term.offset <= c && c < term.offset + term.prep->k) t = term.t;
      res->status = MapSmootherStatus::kInfeasible;
      res->message = fmt::format(
          "infeasible: the multipliers diverge (|u| = {:.1e} at t = {}, {:.0e} times the penalties' bounds and "
          "the data): no state sequence keeps every residual inside its penalty's domain",
          sigma_ * umax, t, umax / (bound_scale * z_scale));
      return true;
    }
    return false;
  }

  // One step on the factored Newton matrix.
  void NewtonStep(double mu) {
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

  int n() const { return kN > 0 ? kN : n_; }

  static std::unique_ptr<Prepared> Prepare(const Penalty& pen, double sigma) {
    auto prep = std::make_unique<Prepared>();
    prep->scaled = pen.plq();
    PlqForm& f = prep->scaled;
    f.p /= sigma;
    f.b /= sigma;
    f.lo /= sigma;
    f.hi /= sigma;
    f.p0 /= sigma * sigma;
    prep->plq = &f;
    prep->k = f.rows();
    prep->m = pen.dim();
    prep->constant = !(f.lo.array().isFinite().any() || f.hi.array().isFinite().any());
    prep->identity_B = f.B.rows() == f.B.cols() && f.B.isIdentity(0.0) && f.b.isZero(0.0) && f.p.isZero(0.0);
    if (prep->constant) {
      Eigen::LLT<Eigen::MatrixXd> llt(f.M);
      IDENT_REQUIRE(llt.info() == Eigen::Success, "{} penalty: M must be positive definite without bounds", pen.Name());
      prep->Kinv = llt.solve(Eigen::MatrixXd::Identity(prep->k, prep->k));
      prep->W = f.B.transpose() * prep->Kinv * f.B;
      prep->c0 = f.p - f.B.transpose() * (prep->Kinv * f.b);
    } else if (!f.diagonal_M) {
      prep->K.resize(prep->k, prep->k);
      prep->KinvB.resize(prep->k, prep->m);
    }
    return prep;
  }

  // r = residual of the term at x (process: x_t - F x_{t-1}; measurement: z_t - H_t x_t), or its
  // linear part J x (include_constant = false).
  IDENT_HOT void Residual(const Term& term, const double* x, bool include_constant, double* out) const {
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
  IDENT_HOT void AddJt(const Term& term, const double* g, double sign, double* out) const {
    const int n = this->n();
    double* ot = out + static_cast<Eigen::Index>(term.t) * n;
    if (term.process) {
      for (int i = 0; i < n; ++i) ot[i] += sign * g[i];
      if (term.F) AddMatTVec<kN, kN>(term.F, n, n, g, ot - n, -sign);
    } else {
      AddMatTVec<0, kN>(term.H, nz_, n, g, ot, -sign);
    }
  }

  // R3 = B r - b - M u - (q_hi - q_lo) per term, R4 = sum J'(p + B'u); returns the scale of p + B'u.
  double Residuals() {
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
  void BalanceOneSidedMultipliers() {
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
  double Complementarity(double a) const {
    double sum = 0;
    for (int c : bounded_) {
      if (has_lo_[c]) sum += (slo_(c) + a * dslo_(c)) * (qlo_(c) + a * dqlo_(c));
      if (has_hi_[c]) sum += (shi_(c) + a * dshi_(c)) * (qhi_(c) + a * dqhi_(c));
    }
    return sum;
  }

  // D = q_hi/s_hi + q_lo/s_lo per coordinate (the barrier curvature C S^-1 Q C').
  IDENT_HOT double BarrierCurvature(int c) const {
    double d = 0;
    if (has_lo_[c]) d += qlo_(c) / slo_(c);
    if (has_hi_[c]) d += qhi_(c) / shi_(c);
    return d;
  }

  // out = K^-1 in for the term (K = M + diag(D)); dense factor computed by AssembleNewtonMatrix.
  IDENT_HOT void ApplyKinv(const Term& term, const double* in, double* out) {
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

  void FactorK(const Term& term) {
    Prepared& prep = *term.prep;
    prep.K = prep.plq->M;
    prep.K.diagonal() += kd_.segment(term.offset, prep.k);
    prep.llt.compute(prep.K);
  }

  // D_t, E_t += J' W J for one term (W: m x m, column-major).
  void AddNewtonBlocks(const Term& term, const double* W, double* D, double* E) {
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
  void AssembleNewtonMatrix() {
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

  // Complementarity residuals R2 = s.*q (+ ds_aff.*dq_aff) - target for coordinate c.
  IDENT_HOT void R2(int c, double target, bool corrector, double* r2lo, double* r2hi) const {
    *r2lo = has_lo_[c] ? slo_(c) * qlo_(c) + (corrector ? xlo_(c) : 0.0) - target : 0.0;
    *r2hi = has_hi_[c] ? shi_(c) * qhi_(c) + (corrector ? xhi_(c) : 0.0) - target : 0.0;
  }

  // Newton direction for F_mu = 0 [ABP eq. (4.3)], with slack s and multiplier q eliminated per term:
  //   (M + D) du = B J dx + R3 - e,   e = S_hi^-1 (-R2_hi + Q_hi R1_hi) - S_lo^-1 (-R2_lo + Q_lo R1_lo)
  //   sum J'B'K^-1 B J dx = -R4 - sum J'B'K^-1 (R3 - e)
  // R1 (the linear box residual u + s - hi, -u + s - (-lo)) is kept in the formulas.
  // Constant terms (no bounds) contribute nothing beyond R4: their R3 - e is 0 (u = K^-1 (B r - b)).
  void Direction(double target, bool corrector) {
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

  IDENT_HOT void RightHandSide(const Term& term, double target, bool corrector, double* rt3) const {
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

  // Largest a keeping s + a ds >= 0 and q + a dq >= 0 (+inf if no component decreases).
  double MaxStep() const {
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

  void Step(double a) {
    x_ += a * dx_;
    u_ += a * du_;
    for (int c : bounded_) {
      slo_(c) += a * dslo_(c);
      qlo_(c) += a * dqlo_(c);
      shi_(c) += a * dshi_(c);
      qhi_(c) += a * dqhi_(c);
    }
  }

  // W = B'K^-1 B of a term at the current iterate (m x m, column-major), K = M + diag(q_hi/s_hi + q_lo/s_lo).
  void TermWeight(const Term& term, double* W) {
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
  void TermDual(const Term& term, double* out) {
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
  void Finish(MapSmootherResult* res, double z_scale, double mu) {
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
  double constant_weight_scale_ = 0;
  double objective_scale_ = 0;  // sum over terms of |v'r| (dual value times residual): the objective's size  // max |W| of the bound-free terms (R4's round-off floor)
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

template <int kN>
MapSmootherResult Solve(const MapSmootherProblem& problem, const MapSmootherOptions& options) {
  Solver<kN> solver(problem, options);
  return solver.Run();
}

#undef IDENT_HOT

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
