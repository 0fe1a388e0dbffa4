#include "ident/map_smoother.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <memory>

#include <Eigen/Cholesky>
#include <fmt/format.h>

#include "ident/block_tridiagonal.h"
#include "ident/common/error.h"

namespace ident {

using models::Penalty;
using models::PlqForm;

const models::Penalty& MapSmootherProblem::ft(int t) const {
  if (process.size() == 1) return process[0];
  if (process.size() == 2) return t == 0 ? process[0] : process[1];
  return process[t];
}

const char* ToString(MapSmootherStatus status) {
  switch (status) {
    case MapSmootherStatus::kConverged: return "converged";
    case MapSmootherStatus::kMaxIterations: return "max_iterations";
    case MapSmootherStatus::kInfeasible: return "infeasible";
    case MapSmootherStatus::kNumericalFailure: return "numerical_failure";
  }
  return "?";
}

std::string MapSmootherOptions::Validate() const {
  if (max_iterations < 1) return fmt::format("max_iterations = {}; need >= 1", max_iterations);
  if (!(tolerance > 0 && tolerance < 1)) return fmt::format("tolerance = {}; need 0 < tolerance < 1", tolerance);
  if (!(step_fraction > 0 && step_fraction < 1))
    return fmt::format("step_fraction = {}; need 0 < step_fraction < 1", step_fraction);
  return "";
}

void ValidateMapSmootherProblem(const MapSmootherProblem& p) {
  IDENT_REQUIRE(p.z.cols() >= 1, "z has no time steps (need T+1 >= 1 columns)");
  IDENT_REQUIRE(p.z.rows() >= 1, "z has no measurement rows");
  IDENT_REQUIRE(p.z.allFinite(), "z has a non-finite entry");
  const int T = p.T();
  IDENT_REQUIRE(p.H.size() == 1 || static_cast<int>(p.H.size()) == T + 1,
                "H has {} matrices; need 1 or T+1 = {}", p.H.size(), T + 1);
  const int n = p.state_dim(), nz = p.measurement_dim();
  IDENT_REQUIRE(n >= 1, "H has no columns (state dimension 0)");
  for (size_t t = 0; t < p.H.size(); ++t) {
    IDENT_REQUIRE(p.H[t].rows() == nz && p.H[t].cols() == n, "H[{}] is {}x{}; need {}x{} (z has {} rows)", t,
                  p.H[t].rows(), p.H[t].cols(), nz, n, nz);
    IDENT_REQUIRE(p.H[t].allFinite(), "H[{}] has a non-finite entry", t);
  }
  if (T > 0) {
    IDENT_REQUIRE(p.F.size() == 1 || static_cast<int>(p.F.size()) == T, "F has {} matrices; need 1 or T = {}",
                  p.F.size(), T);
    for (size_t t = 0; t < p.F.size(); ++t) {
      IDENT_REQUIRE(p.F[t].rows() == n && p.F[t].cols() == n, "F[{}] is {}x{}; need {}x{}", t, p.F[t].rows(),
                    p.F[t].cols(), n, n);
      IDENT_REQUIRE(p.F[t].allFinite(), "F[{}] has a non-finite entry", t);
    }
  }
  const size_t np = p.process.size();
  IDENT_REQUIRE(np == 1 || np == 2 || static_cast<int>(np) == T + 1,
                "process has {} penalties; need 1, 2 (initial, then all t) or T+1 = {}", np, T + 1);
  for (size_t t = 0; t < np; ++t)
    IDENT_REQUIRE(p.process[t].dim() == n, "process penalty {} has dimension {}; the state has {}", t,
                  p.process[t].dim(), n);
  IDENT_REQUIRE(p.measurement.size() == 1 || static_cast<int>(p.measurement.size()) == T + 1,
                "measurement has {} penalties; need 1 or T+1 = {}", p.measurement.size(), T + 1);
  for (size_t t = 0; t < p.measurement.size(); ++t)
    IDENT_REQUIRE(p.measurement[t].dim() == nz, "measurement penalty {} has dimension {}; z has {} rows", t,
                  p.measurement[t].dim(), nz);
}

double PrimalObjective(const MapSmootherProblem& p, const Eigen::MatrixXd& x, double domain_tolerance) {
  ValidateMapSmootherProblem(p);
  IDENT_REQUIRE(x.rows() == p.state_dim() && x.cols() == p.T() + 1, "x is {}x{}; need {}x{}", x.rows(), x.cols(),
                p.state_dim(), p.T() + 1);
  double sum = 0;
  Eigen::VectorXd w;
  for (int t = 0; t <= p.T(); ++t) {
    w = x.col(t);
    if (t > 0) w.noalias() -= p.Ft(t - 1) * x.col(t - 1);
    sum += p.ft(t).Value(w, domain_tolerance);
    sum += p.gt(t).Value(p.z.col(t) - p.Ht(t) * x.col(t), domain_tolerance);
  }
  return sum;
}

Eigen::MatrixXd DualStates(const MapSmootherProblem& p, const Eigen::MatrixXd& u) {
  ValidateMapSmootherProblem(p);
  IDENT_REQUIRE(u.rows() == p.measurement_dim() && u.cols() == p.T() + 1, "u is {}x{}; need {}x{}", u.rows(),
                u.cols(), p.measurement_dim(), p.T() + 1);
  const int T = p.T();
  Eigen::MatrixXd y(p.state_dim(), T + 1);
  y.col(T) = p.Ht(T).transpose() * u.col(T);  // y_T = H_T'u_T
  for (int t = T - 1; t >= 0; --t)              // y_t = F_t'y_{t+1} + H_t'u_t   [BCW Thm 2.5, A'y = H'u]
    y.col(t) = p.Ft(t).transpose() * y.col(t + 1) + p.Ht(t).transpose() * u.col(t);
  return y;
}

double DualObjective(const MapSmootherProblem& p, const Eigen::MatrixXd& u) {
  const Eigen::MatrixXd y = DualStates(p, u);
  double sum = 0;
  for (int t = 0; t <= p.T(); ++t)  // z'u - g*(u) - f*(y)   [BCW eq. (6)]
    sum += p.z.col(t).dot(u.col(t)) - p.gt(t).Conjugate(u.col(t)) - p.ft(t).Conjugate(y.col(t));
  return sum;
}

Eigen::MatrixXd StatesFromDual(const MapSmootherProblem& p, const Eigen::MatrixXd& y) {
  ValidateMapSmootherProblem(p);
  IDENT_REQUIRE(y.rows() == p.state_dim() && y.cols() == p.T() + 1, "y is {}x{}; need {}x{}", y.rows(), y.cols(),
                p.state_dim(), p.T() + 1);
  Eigen::MatrixXd x(p.state_dim(), p.T() + 1);
  for (int t = 0; t <= p.T(); ++t) {
    x.col(t) = p.ft(t).ConjugateGradient(y.col(t));  // w_t in d f_t*(y_t)   [BCW sec. 3]
    if (t > 0) x.col(t) += p.Ft(t - 1) * x.col(t - 1);
  }
  return x;
}

namespace {

// y += alpha A x and y += alpha A' x with plain loops (A column-major): for the small matrices of
// state-space smoothing these are several times faster than Eigen's dynamic-size kernels.
inline void AddMatVec(const Eigen::MatrixXd& A, const double* x, double* y, double alpha) {
  const Eigen::Index r = A.rows(), c = A.cols();
  const double* a = A.data();
  for (Eigen::Index j = 0; j < c; ++j) {
    const double xj = alpha * x[j];
    for (Eigen::Index i = 0; i < r; ++i) y[i] += a[i + j * r] * xj;
  }
}
inline void AddMatTVec(const Eigen::MatrixXd& A, const double* x, double* y, double alpha) {
  const Eigen::Index r = A.rows(), c = A.cols();
  const double* a = A.data();
  for (Eigen::Index j = 0; j < c; ++j) {
    double s = 0;
    for (Eigen::Index i = 0; i < r; ++i) s += a[i + j * r] * x[i];
    y[j] += alpha * s;
  }
}

// Solver-side data of one distinct penalty.
struct Prepared {
  const PlqForm* plq = nullptr;
  int k = 0, m = 0;
  bool constant = false;   // no finite bound: K = M, W = B'M^-1 B fixed
  Eigen::MatrixXd Kinv;    // constant case
  Eigen::MatrixXd W;       // constant case
  Eigen::MatrixXd K;       // dense case work
  Eigen::LLT<Eigen::MatrixXd> llt;
  Eigen::MatrixXd KinvB;   // dense case work (k x m)
};

struct Term {
  Prepared* prep;
  int offset;  // into the coordinate arrays
  int t;
  bool process;
};

class Solver {
 public:
  Solver(const MapSmootherProblem& p, const MapSmootherOptions& o)
      : p_(p), o_(o), T_(p.T()), n_(p.state_dim()), nz_(p.measurement_dim()), chol_(n_, T_ + 1) {
    int offset = 0;
    for (int pass = 0; pass < 2; ++pass)
      for (int t = 0; t <= T_; ++t) {
        const Penalty& pen = pass == 0 ? p.ft(t) : p.gt(t);
        auto it = prepared_.find(&pen);
        if (it == prepared_.end()) it = prepared_.emplace(&pen, Prepare(pen)).first;
        terms_.push_back({it->second.get(), offset, t, pass == 0});
        offset += it->second->k;
      }
    const int K = offset;
    for (Eigen::VectorXd* v : {&u_, &slo_, &qlo_, &shi_, &qhi_, &lo_, &hi_, &r3_, &du_, &dslo_, &dqlo_, &dshi_,
                               &dqhi_, &xlo_, &xhi_, &kd_})
      v->setZero(K);
    rt3_.setZero(K);
    has_lo_.assign(K, 0);
    has_hi_.assign(K, 0);
    for (const Term& term : terms_) {
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
      }
    }
    for (const auto& F : p.F) matrix_scale_ = std::max(matrix_scale_, 1 + F.cwiseAbs().maxCoeff());
    for (const auto& H : p.H) matrix_scale_ = std::max(matrix_scale_, 1 + H.cwiseAbs().maxCoeff());
    x_.setZero(n_, T_ + 1);
    R4_.setZero(n_, T_ + 1);
    dx_.setZero(n_, T_ + 1);
    D_.setZero(n_, static_cast<Eigen::Index>(n_) * (T_ + 1));
    E_.setZero(n_, static_cast<Eigen::Index>(n_) * (T_ + 1));
    const int m = std::max(n_, nz_);
    r_.resize(m);
    v_.resize(m);
    g_.resize(m);
    W_.resize(m, m);
    WF_.resize(m, n_);
    int kmax = 1;
    for (auto& [_, prep] : prepared_) kmax = std::max(kmax, prep->k);
    tk_.resize(kmax);
    tk2_.resize(kmax);
  }

  MapSmootherResult Run() {
    MapSmootherResult res;
    const double z_scale = 1 + p_.z.cwiseAbs().maxCoeff();
    double bound_scale = 1;
    for (int c = 0; c < u_.size(); ++c) {
      if (has_lo_[c]) bound_scale = std::max(bound_scale, std::abs(lo_(c)));
      if (has_hi_[c]) bound_scale = std::max(bound_scale, std::abs(hi_(c)));
    }
    res.status = MapSmootherStatus::kMaxIterations;
    int iter = 0;
    for (;; ++iter) {
      const double v_scale = Residuals();
      const double mu = num_constraints_ ? Complementarity(0) / num_constraints_ : 0.0;
      const double r3max = r3_.size() ? r3_.cwiseAbs().maxCoeff() : 0.0;
      const double r4max = R4_.cwiseAbs().maxCoeff();
      // KKT residual relative to its scale (R4 sums products of H_t, F_t with p + B'u).
      const double kkt = std::max({mu, r3max / z_scale, r4max / (v_scale * matrix_scale_)});
      res.kkt_residual = kkt;
      if (kkt <= o_.tolerance) {
        res.status = MapSmootherStatus::kConverged;
        break;
      }
      if (iter >= o_.max_iterations) break;
      if (u_.size() && u_.cwiseAbs().maxCoeff() > 1e10 * bound_scale * z_scale) {
        res.status = MapSmootherStatus::kInfeasible;
        break;
      }
      AssembleNewtonMatrix();
      if (!chol_.Factorize(D_, E_)) {
        // Near the solution K = M + D spans many orders of magnitude; if the Newton matrix breaks down
        // there, the iterate is accepted when its KKT residual is within 1e3 tolerance (precision limit).
        res.status = kkt <= 1e3 * o_.tolerance ? MapSmootherStatus::kConverged : MapSmootherStatus::kNumericalFailure;
        break;
      }
      if (num_constraints_ == 0) {  // all penalties quadratic: one Newton step solves (P) exactly
        Direction(0.0, false);
        Step(1.0);
        continue;
      }
      // Mehrotra predictor-corrector: affine direction, centring sigma = (mu_aff / mu)^3, then the
      // corrected direction with the second-order term ds_aff .* dq_aff.
      Direction(0.0, false);
      const double alpha_aff = std::min(1.0, MaxStep());
      const double mu_aff = Complementarity(alpha_aff) / num_constraints_;
      const double sigma = std::pow(std::clamp(mu_aff / mu, 0.0, 1.0), 3);
      xlo_ = dslo_.cwiseProduct(dqlo_);
      xhi_ = dshi_.cwiseProduct(dqhi_);
      Direction(sigma * mu, true);
      Step(std::min(1.0, o_.step_fraction * MaxStep()));
    }
    res.iterations = iter;
    switch (res.status) {
      case MapSmootherStatus::kConverged:
        res.message = fmt::format("converged in {} iterations (KKT residual {:.1e})", iter, res.kkt_residual);
        break;
      case MapSmootherStatus::kMaxIterations:
        res.message = fmt::format("did not converge in {} iterations (the problem may be infeasible)", iter);
        break;
      case MapSmootherStatus::kInfeasible:
        res.message = "the multipliers diverge: no state sequence keeps every residual inside its penalty's domain";
        break;
      case MapSmootherStatus::kNumericalFailure: res.message = "the Newton matrix is not positive definite"; break;
    }
    Finish(&res, z_scale);
    return res;
  }

 private:
  static std::unique_ptr<Prepared> Prepare(const Penalty& pen) {
    auto prep = std::make_unique<Prepared>();
    const PlqForm& f = pen.plq();
    prep->plq = &f;
    prep->k = f.rows();
    prep->m = pen.dim();
    prep->constant = !(f.lo.array().isFinite().any() || f.hi.array().isFinite().any());
    if (prep->constant) {
      Eigen::LLT<Eigen::MatrixXd> llt(f.M);
      IDENT_REQUIRE(llt.info() == Eigen::Success, "{} penalty: M must be positive definite without bounds",
                    pen.Name());
      prep->Kinv = llt.solve(Eigen::MatrixXd::Identity(prep->k, prep->k));
      prep->W = f.B.transpose() * prep->Kinv * f.B;
    } else if (!f.diagonal_M) {
      prep->K.resize(prep->k, prep->k);
      prep->KinvB.resize(prep->k, prep->m);
    }
    return prep;
  }

  // r = residual of the term at x (process: x_t - F x_{t-1}; measurement: z_t - H_t x_t).
  void Residual(const Term& term, const Eigen::MatrixXd& x, bool include_constant, Eigen::Ref<Eigen::VectorXd> r) {
    const int t = term.t;
    double* out = r.data();
    if (term.process) {
      const double* xt = x.data() + static_cast<Eigen::Index>(t) * n_;
      for (int i = 0; i < n_; ++i) out[i] = xt[i];
      if (t > 0) AddMatVec(p_.Ft(t - 1), xt - n_, out, -1.0);
    } else {
      for (int i = 0; i < nz_; ++i) out[i] = include_constant ? p_.z(i, t) : 0.0;
      AddMatVec(p_.Ht(t), x.data() + static_cast<Eigen::Index>(t) * n_, out, -1.0);
    }
  }

  // out += sign * J' g
  void AddJt(const Term& term, const Eigen::Ref<const Eigen::VectorXd>& g, double sign, Eigen::MatrixXd& out) {
    const int t = term.t;
    double* ot = out.data() + static_cast<Eigen::Index>(t) * n_;
    if (term.process) {
      for (int i = 0; i < n_; ++i) ot[i] += sign * g(i);
      if (t > 0) AddMatTVec(p_.Ft(t - 1), g.data(), ot - n_, -sign);
    } else {
      AddMatTVec(p_.Ht(t), g.data(), ot, -sign);
    }
  }

  // R3 = B r - b - M u - (q_hi - q_lo) per term, R4 = sum J'(p + B'u); returns the scale of p + B'u.
  double Residuals() {
    R4_.setZero();
    double v_scale = 1;
    for (const Term& term : terms_) {
      const PlqForm& f = *term.prep->plq;
      const int m = term.prep->m, k = term.prep->k;
      auto r = r_.head(m);
      auto v = v_.head(m);
      Residual(term, x_, true, r);
      auto u = u_.segment(term.offset, k);
      v = f.p;
      AddMatTVec(f.B, u.data(), v.data(), 1.0);
      v_scale = std::max(v_scale, v.cwiseAbs().maxCoeff());
      AddJt(term, v, 1.0, R4_);
      auto r3 = r3_.segment(term.offset, k);
      r3 = -f.b;
      AddMatVec(f.B, r.data(), r3.data(), 1.0);
      if (f.diagonal_M)
        r3 -= f.M.diagonal().cwiseProduct(u);
      else
        r3.noalias() -= f.M * u;
      r3 -= qhi_.segment(term.offset, k) - qlo_.segment(term.offset, k);
    }
    return v_scale;
  }

  // sum (s + a ds) .* (q + a dq) over finite bounds.
  double Complementarity(double a) const {
    double sum = 0;
    for (int c = 0; c < u_.size(); ++c) {
      if (has_lo_[c]) sum += (slo_(c) + a * dslo_(c)) * (qlo_(c) + a * dqlo_(c));
      if (has_hi_[c]) sum += (shi_(c) + a * dshi_(c)) * (qhi_(c) + a * dqhi_(c));
    }
    return sum;
  }

  // D = q_hi/s_hi + q_lo/s_lo per coordinate (the barrier curvature C S^-1 Q C').
  double BarrierCurvature(int c) const {
    double d = 0;
    if (has_lo_[c]) d += qlo_(c) / slo_(c);
    if (has_hi_[c]) d += qhi_(c) / shi_(c);
    return d;
  }

  // tk2 = K^-1 tk for the term (K = M + diag(D)); dense factor computed by AssembleNewtonMatrix.
  void ApplyKinv(const Term& term, Eigen::Ref<Eigen::VectorXd> tk, Eigen::Ref<Eigen::VectorXd> out) {
    Prepared& prep = *term.prep;
    if (prep.constant) {
      out.setZero();
      AddMatVec(prep.Kinv, tk.data(), out.data(), 1.0);
    } else if (prep.plq->diagonal_M) {
      out = tk.cwiseQuotient(kd_.segment(term.offset, prep.k));
    } else {
      FactorK(term);
      out = prep.llt.solve(tk);
    }
  }

  void FactorK(const Term& term) {
    Prepared& prep = *term.prep;
    prep.K = prep.plq->M;
    prep.K.diagonal() += kd_.segment(term.offset, prep.k);
    prep.llt.compute(prep.K);
  }

  // D_, E_ = sum_terms J' B' K^-1 B J   (block tridiagonal)
  void AssembleNewtonMatrix() {
    D_.setZero();
    E_.setZero();
    for (const Term& term : terms_) {
      Prepared& prep = *term.prep;
      const PlqForm& f = *prep.plq;
      const int m = prep.m, k = prep.k;
      auto W = W_.topLeftCorner(m, m);
      if (prep.constant) {
        W = prep.W;
      } else {
        for (int i = 0; i < k; ++i)
          kd_(term.offset + i) = BarrierCurvature(term.offset + i) + (f.diagonal_M ? f.M(i, i) : 0.0);
        if (f.diagonal_M) {
          W.setZero();
          for (int i = 0; i < k; ++i) {
            const double inv = 1.0 / kd_(term.offset + i);
            for (int a = 0; a < m; ++a)
              for (int b = 0; b < m; ++b) W(a, b) += f.B(i, a) * f.B(i, b) * inv;
          }
        } else {
          for (int i = 0; i < k; ++i) kd_(term.offset + i) = BarrierCurvature(term.offset + i);
          FactorK(term);
          prep.KinvB = prep.llt.solve(f.B);
          W.noalias() = f.B.transpose() * prep.KinvB;
        }
      }
      const int t = term.t;
      double* Dt = D_.data() + static_cast<Eigen::Index>(t) * n_ * n_;
      if (term.process) {
        for (int b = 0; b < n_; ++b)
          for (int a = 0; a < n_; ++a) Dt[a + b * n_] += W(a, b);
        if (t > 0) {  // D_{t-1} += F'WF,  E_t -= W F
          const Eigen::MatrixXd& F = p_.Ft(t - 1);
          double* Dp = Dt - static_cast<Eigen::Index>(n_) * n_;
          double* Et = E_.data() + static_cast<Eigen::Index>(t) * n_ * n_;
          for (int b = 0; b < n_; ++b)
            for (int a = 0; a < n_; ++a) {
              double wf = 0;
              for (int c = 0; c < n_; ++c) wf += W(a, c) * F(c, b);
              WF_(a, b) = wf;
              Et[a + b * n_] -= wf;
            }
          for (int b = 0; b < n_; ++b)
            for (int a = 0; a < n_; ++a) {
              double s = 0;
              for (int c = 0; c < n_; ++c) s += F(c, a) * WF_(c, b);
              Dp[a + b * n_] += s;
            }
        }
      } else {  // D_t += H'WH
        const Eigen::MatrixXd& H = p_.Ht(t);
        for (int b = 0; b < n_; ++b)
          for (int a = 0; a < nz_; ++a) {
            double wh = 0;
            for (int c = 0; c < nz_; ++c) wh += W(a, c) * H(c, b);
            WF_(a, b) = wh;
          }
        for (int b = 0; b < n_; ++b)
          for (int a = 0; a < n_; ++a) {
            double s = 0;
            for (int c = 0; c < nz_; ++c) s += H(c, a) * WF_(c, b);
            Dt[a + b * n_] += s;
          }
      }
    }
  }

  // Complementarity residuals R2 = s.*q (+ ds_aff.*dq_aff) - target for coordinate c.
  void R2(int c, double target, bool corrector, double* r2lo, double* r2hi) const {
    *r2lo = has_lo_[c] ? slo_(c) * qlo_(c) + (corrector ? xlo_(c) : 0.0) - target : 0.0;
    *r2hi = has_hi_[c] ? shi_(c) * qhi_(c) + (corrector ? xhi_(c) : 0.0) - target : 0.0;
  }

  // Newton direction for F_mu = 0 [ABP eq. (4.3)], with slack s and multiplier q eliminated per term:
  //   (M + D) du = B J dx + R3 - e,   e = S_hi^-1 (-R2_hi + Q_hi R1_hi) - S_lo^-1 (-R2_lo + Q_lo R1_lo)
  //   sum J'B'K^-1 B J dx = -R4 - sum J'B'K^-1 (R3 - e)
  // R1 (the linear box residual u + s - hi, -u + s - (-lo)) is kept in the formulas.
  void Direction(double target, bool corrector) {
    dx_ = -R4_;
    for (const Term& term : terms_) {
      const int k = term.prep->k, m = term.prep->m;
      auto rt3 = rt3_.segment(term.offset, k);
      RightHandSide(term, target, corrector, rt3);
      auto kinv = tk2_.head(k);
      ApplyKinv(term, rt3, kinv);
      auto g = g_.head(m);
      g.setZero();
      AddMatTVec(term.prep->plq->B, kinv.data(), g.data(), 1.0);
      AddJt(term, g, -1.0, dx_);
    }
    chol_.Solve(dx_);
    for (const Term& term : terms_) {
      const int k = term.prep->k, m = term.prep->m;
      auto rt3 = tk_.head(k);
      rt3 = rt3_.segment(term.offset, k);
      auto r = r_.head(m);
      Residual(term, dx_, false, r);  // J dx
      AddMatVec(term.prep->plq->B, r.data(), rt3.data(), 1.0);
      auto du = du_.segment(term.offset, k);
      ApplyKinv(term, rt3, du);
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

  void RightHandSide(const Term& term, double target, bool corrector, Eigen::Ref<Eigen::VectorXd> rt3) const {
    const int k = term.prep->k;
    for (int i = 0; i < k; ++i) {
      const int c = term.offset + i;
      double r2lo, r2hi;
      R2(c, target, corrector, &r2lo, &r2hi);
      double e = 0;
      if (has_hi_[c]) e += (-r2hi + qhi_(c) * (u_(c) + shi_(c) - hi_(c))) / shi_(c);
      if (has_lo_[c]) e -= (-r2lo + qlo_(c) * (-u_(c) + slo_(c) + lo_(c))) / slo_(c);
      rt3(i) = r3_(c) - e;
    }
  }

  // Largest a keeping s + a ds >= 0 and q + a dq >= 0 (+inf if no component decreases).
  double MaxStep() const {
    double a = std::numeric_limits<double>::infinity();
    auto limit = [&a](double value, double delta) {
      if (delta < 0) a = std::min(a, -value / delta);
    };
    for (int c = 0; c < u_.size(); ++c) {
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
    slo_ += a * dslo_;
    qlo_ += a * dqlo_;
    shi_ += a * dshi_;
    qhi_ += a * dqhi_;
  }

  void Finish(MapSmootherResult* res, double z_scale) {
    res->x = x_;
    res->w.resize(n_, T_ + 1);
    for (int t = 0; t <= T_; ++t) {
      res->w.col(t) = x_.col(t);
      if (t > 0) res->w.col(t) -= p_.Ft(t - 1) * x_.col(t - 1);
    }
    res->u.resize(nz_, T_ + 1);
    for (const Term& term : terms_) {
      if (term.process) continue;
      const PlqForm& f = *term.prep->plq;
      res->u.col(term.t) = f.p + f.B.transpose() * u_.segment(term.offset, term.prep->k);  // u_t in d g_t
    }
    // Dual point: u from the multipliers, y from u by the dynamics of (D) (exact A'y = H'u). Rounding can
    // leave u_t, y_t a hair outside a box dom f*, dom g*: the distance is reported and the point projected.
    auto project = [&](const Penalty& pen, Eigen::Ref<Eigen::VectorXd> v) {
      double violation = 0;
      for (int i = 0; i < v.size(); ++i) {
        const double c = std::clamp(v(i), pen.conjugate_lo()(i), pen.conjugate_hi()(i));
        violation = std::max(violation, std::abs(c - v(i)));
        v(i) = c;
      }
      res->dual_infeasibility = std::max(res->dual_infeasibility, violation);
    };
    for (int t = 0; t <= T_; ++t) project(p_.gt(t), res->u.col(t));
    res->y = DualStates(p_, res->u);
    for (int t = 0; t <= T_; ++t) project(p_.ft(t), res->y.col(t));
    double dual = 0;
    for (int t = 0; t <= T_; ++t)
      dual += p_.z.col(t).dot(res->u.col(t)) - p_.gt(t).Conjugate(res->u.col(t)) - p_.ft(t).Conjugate(res->y.col(t));
    res->dual = dual;
    res->primal = PrimalObjective(p_, x_, 1e-8 * z_scale);
    res->gap = res->primal - res->dual;
    res->relative_gap = res->gap / std::max(1.0, std::abs(res->primal));
    // w_t in d f_t*(y_t) is unique where f_t* is differentiable: y_t strictly inside the box dom f_t*,
    // and for Vapnik (eps |y|) also y_t != 0. On the boundary the normal cone adds freedom, so the
    // rebuilt states need not equal x (reported via reconstruction_unique).
    res->reconstruction_unique = true;
    for (int t = 0; t <= T_; ++t) {
      const Penalty& f = p_.ft(t);
      for (int i = 0; i < n_; ++i) {
        const double v = res->y(i, t), lo = f.conjugate_lo()(i), hi = f.conjugate_hi()(i);
        const double margin = 1e-7 * (1 + std::abs(v));
        if (v - lo <= margin || hi - v <= margin) res->reconstruction_unique = false;
        if (f.kind() == Penalty::Kind::kVapnik && std::abs(v) <= margin) res->reconstruction_unique = false;
      }
    }
    res->x_from_dual = StatesFromDual(p_, res->y);
    res->max_abs_x_difference = (res->x_from_dual - x_).cwiseAbs().maxCoeff();
  }

  const MapSmootherProblem& p_;
  const MapSmootherOptions& o_;
  const int T_, n_, nz_;
  std::map<const Penalty*, std::unique_ptr<Prepared>> prepared_;
  std::vector<Term> terms_;
  int num_constraints_ = 0;
  double matrix_scale_ = 1;
  // Per PLQ coordinate: u, slacks and multipliers of lo <= u <= hi, residual R3, Newton direction,
  // affine cross terms ds.*dq, and K's diagonal.
  std::vector<char> has_lo_, has_hi_;  // finite bounds per coordinate
  Eigen::VectorXd rt3_;                // R3 - e of the current direction (first pass of Direction)
  Eigen::VectorXd u_, slo_, qlo_, shi_, qhi_, lo_, hi_, r3_, du_, dslo_, dqlo_, dshi_, dqhi_, xlo_, xhi_, kd_;
  Eigen::MatrixXd x_, R4_, dx_, D_, E_;
  Eigen::VectorXd r_, v_, g_, tk_, tk2_;
  Eigen::MatrixXd W_, WF_;
  BlockTridiagonalCholesky chol_;
};

}  // namespace

MapSmootherResult SolveMapSmoother(const MapSmootherProblem& problem, const MapSmootherOptions& options) {
  ValidateMapSmootherProblem(problem);
  const std::string error = options.Validate();
  IDENT_REQUIRE(error.empty(), "MapSmootherOptions: {}", error);
  Solver solver(problem, options);
  return solver.Run();
}

}  // namespace ident
