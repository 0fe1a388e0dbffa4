// The normalised statistics (ν, V) shared by RLS and the Kárný–Hangos estimators, with V held in
// L'DL form. One step of every such estimator is
//
//   1. forgetting:   exponential  ν̃ = λν,  Ṽ = V                                       [spec §7b]
//                    stabilised   ν̃ = λν + (1−λ)ν_a,  Ṽ = [λνV + (1−λ)ν_a V_a]/ν̃
//   2. ν(t) = ν̃ + 1
//   3. innovation:   h = [y; z],  L'g = h  ⇒  ê = g_0,  ξ_z = 1 − Σ_{i≥1} g_i²/d_i,
//                    ξ = ξ_z − ê²/d_0   (ξ = 1 − h'Ṽ⁻¹h, ξ_z = 1 − z'Ṽ_z⁻¹z)          [spec §3, §6]
//   4. the estimator chooses β(t) (RLS: 1/ν; Kárný–Hangos: root of the weighting cubic)
//   5. V(t) = (1−β)Ṽ + β h h'   (d ← (1−β)d, then the rank-one update with c = β, a = h)
//
// Read-outs: Θ̂ = L_z⁻¹ l_zy (forward substitution, cached), D_y = d_0, V_z⁻¹ (on demand).
// Index 0 of V is y; L = [[1, 0], [l_zy, L_z]], D = diag(d_y, D_z).
//
// Step 5 also comes in two phases, PlanApply() (O(ρ): the new d and what bounds the new L, state
// unchanged) and CommitApply() (the O(ρ²) update), so that ident/regression/internal/step_guard.h can decide before
// touching the state.
//
// All operations after construction are allocation-free except VzInverse() and V() (ScaledVzInverse()
// is the allocation-free alternative to VzInverse()).
#pragma once

#include <cmath>
#include <limits>
#include <type_traits>

#include <Eigen/Core>

#include "common/error.h"
#include "ident/linalg/ld_factor.h"
#include "ident/regression/regression_prior.h"

namespace ident {

// ξ, ξ_z and ê of one data item against Ṽ [spec §3].
struct Innovation {
  double xi = 0;                // 1 − h'Ṽ⁻¹h
  double xi_z = 0;              // 1 − z'Ṽ_z⁻¹z
  double prediction_error = 0;  // ê = y − Θ̂'z
};

// Dim = ρ+1 (the size of V) or Eigen::Dynamic.
template <int Dim = Eigen::Dynamic>
class ExtendedInformation {
 public:
  using Vector = Eigen::Matrix<double, Dim, 1>;
  using ParamVector = Eigen::Matrix<double, (Dim == Eigen::Dynamic ? Eigen::Dynamic : Dim - 1), 1>;

  explicit ExtendedInformation(const RegressionPrior& prior) { Reset(prior); }

  void Reset(const RegressionPrior& prior) {
    prior.Validate();
    nu_ = prior.nu0;
    V_.Factorize(prior.V0);
    const int n = V_.size();
    h_.resize(n);
    g_.resize(n);
    inv_d_.resize(n);
    q_sum_.resize(n);
    theta_.resize(n - 1);
    theta_valid_ = false;
  }

  // Back to (ν0, V0) given in factored form (e.g. a factor kept from construction). No allocation when
  // V0 has the current size; never throws.
  void Reset(double nu0, const LdFactor<Dim>& V0) noexcept {
    nu_ = nu0;
    V_ = V0;
    theta_valid_ = false;
  }

  int num_parameters() const { return V_.size() - 1; }
  double nu() const { return nu_; }
  double Dy() const { return V_.d()(0); }
  const LdFactor<Dim>& factor() const { return V_; }

  // Step 1, exponential: ν̃ = λν (exact: V is normalised) [spec §7b].
  void ForgetExponential(double lambda) { nu_ *= lambda; }

  // Step 1, stabilised towards (ν_a, V_a): d ← (λν/ν̃)d, then one rank-one update per row of L_a
  // with c = (1−λ)ν_a d_{a,i}/ν̃ (V_a = Σ_i d_{a,i} l_i l_i', l_i = row i of L_a). O(ρ³) [spec §7b].
  void ForgetStabilised(double lambda, double nu_a, const LdFactor<Dim>& Va) {
    if (lambda == 1.0) return;
    const double nu_tilde = lambda * nu_ + (1 - lambda) * nu_a;
    V_.ScaleD(lambda * nu_ / nu_tilde);
    const int n = V_.size();
    for (int i = 0; i < n; ++i) {
      g_.setZero();
      g_.head(i + 1) = Va.L().row(i).head(i + 1).transpose();
      V_.RankOneUpdate((1 - lambda) * nu_a * Va.d()(i) / nu_tilde, g_);
    }
    nu_ = nu_tilde;
    theta_valid_ = false;
  }

  // Step 3: stores h = [y; z] for Apply() and returns ξ, ξ_z, ê against the current (forgotten) V.
  // With_xi = false computes ê only (ξ = ξ_z = NaN): RLS needs no ξ and saves ρ+1 divisions.
  template <bool WithXi = true, class Derived>
  Innovation Prepare(double y, const Eigen::MatrixBase<Derived>& z) {
    // g and h are both written from (y, z) (not g copied from h: a wide load of h just after its
    // narrow stores cannot be store-forwarded and stalls the update's critical path).
    LoadSample(y, z);
    kept_ = WithXi;
    if constexpr (!WithXi) {
      V_.SolveTransposed(g_, g_);
      constexpr double nan = std::numeric_limits<double>::quiet_NaN();
      return {nan, nan, g_(0)};
    }
    // r_i = 1/d_i need not wait for g; the running sums Q_j = Σ_{i≥j} g_i² r_i give ξ_z = 1 − Q_1,
    // ξ = ξ_z − g_0² r_0, and are kept with r for PlanApply<true>() (LdFactor::PlanUpdateFromSums).
    const auto& d = V_.d();
    const Eigen::Index n = g_.size();
    for (Eigen::Index i = 0; i < n; ++i) inv_d_(i) = 1 / d(i);
    V_.SolveTransposedKeep(g_);  // partial sums kept for CommitApply()
    double zeta = 0;
    for (Eigen::Index i = n - 1; i >= 1; --i) {
      zeta += g_(i) * g_(i) * inv_d_(i);
      q_sum_(i) = zeta;
    }
    const double e2 = g_(0) * g_(0) * inv_d_(0);
    q_sum_(0) = zeta + e2;
    Innovation in;
    in.prediction_error = g_(0);
    in.xi_z = 1 - zeta;
    in.xi = in.xi_z - e2;
    return in;
  }

  // Step 5: V ← (1−β)V + β h h' with the h of the last Prepare(); ν ← nu_new. Requires 0 < β < 1.
  void Apply(double beta, double nu_new) {
    PlanApply(beta);
    CommitApply(nu_new, h_.cwiseAbs().maxCoeff());
  }
  // Step 5 in two phases (see LdFactor::PlanUpdate): the plan gives the new d (and what bounds the
  // new L) in O(ρ) from the g of Prepare(), without changing anything, so that a guard can decide
  // before the state is touched (ident/regression/internal/step_guard.h); the commit applies it.
  // WithXi = true: after Prepare<true>(), from the reciprocals and sums it kept (same plan, fewer
  // divisions after β is known; LdFactor::PlanUpdateFromSums).
  template <bool WithXi = false>
  const typename LdFactor<Dim>::Plan& PlanApply(double beta) noexcept {
    if constexpr (WithXi)
      return V_.PlanUpdateFromSums(1 - beta, beta, g_, inv_d_, q_sum_);
    else
      return V_.PlanUpdate(1 - beta, beta, g_);
  }
  // `h_bound` ≥ max_i |h_i| (e.g. the 2-norm of h), for the factor's bound on max|L|.
  // After Prepare<true>() the commit reuses the back substitution's partial sums (LdFactor::CommitSolved).
  void CommitApply(double nu_new, double h_bound) noexcept {
    if (kept_) {
      V_.CommitSolved(g_, h_bound);
    } else {
      g_ = h_;
      V_.CommitUpdate(g_, h_bound);
    }
    nu_ = nu_new;
    theta_valid_ = false;
  }
  // Steps 3 and 5 in one sweep, for a β known before the innovation (RLS: β = 1/ν): h = [y; z], the back
  // substitution (ê = g_0, returned in `prediction_error`), the plan and the new L (LdFactor::PlanFused: the
  // numbers of Prepare<false>() and PlanApply<false>(β), one O(ρ²) pass fewer). Then CommitFused(), or
  // RollbackFused() for the state bit-identical to before (L and d are updated in place, the old ones kept).
  template <class Derived>
  const typename LdFactor<Dim>::Plan& PrepareAndPlan(double y, const Eigen::MatrixBase<Derived>& z, double beta,
                                                     double& prediction_error) noexcept {
    LoadSample(y, z);
    const auto& plan = V_.PlanFused(1 - beta, beta, g_, h_);
    prediction_error = g_(0);
    return plan;
  }
  // Commits the last PrepareAndPlan(); ν ← nu_new, `h_bound` as for CommitApply().
  void CommitFused(double nu_new, double h_bound) noexcept {
    V_.CommitFused(h_bound);
    nu_ = nu_new;
    theta_valid_ = false;
  }
  // Undoes the last PrepareAndPlan() (and CommitFused(), if it was called); ν ← nu.
  void RollbackFused(double nu) noexcept {
    V_.RollbackFused();
    nu_ = nu;
    theta_valid_ = false;
  }
  // ν only (undoes ForgetExponential).
  void RestoreNu(double nu) noexcept { nu_ = nu; }

  // Θ̂ = L_z⁻¹ l_zy (forward substitution, cached until the next change). Four columns at a time: once Θ̂_j …
  // Θ̂_(j+3) are final they are taken off every later entry, in the order j, j + 1, … per entry (the rounding of
  // a row-by-row dot product), but the entries' updates are independent of one another (a dot product chains
  // each row's subtractions through one accumulator, and waits for the entry just solved).
  const ParamVector& parameters() const {
    if (!theta_valid_) {
      const auto& L = V_.L();
      static_assert(std::decay_t<decltype(L)>::IsRowMajor, "the blocks below read L(i, j … j + 3) contiguously");
      const Eigen::Index rho = theta_.size();
      double* const theta = theta_.data();
      for (Eigen::Index i = 0; i < rho; ++i) theta[i] = L(i + 1, 0);
      Eigen::Index j = 0;
      for (; j + 3 < rho; j += 4) {
        const double t0 = theta[j];
        const double t1 = theta[j + 1] -= L(j + 2, j + 1) * t0;
        const double t2 = theta[j + 2] = (theta[j + 2] - L(j + 3, j + 1) * t0) - L(j + 3, j + 2) * t1;
        const double t3 = theta[j + 3] =
            ((theta[j + 3] - L(j + 4, j + 1) * t0) - L(j + 4, j + 2) * t1) - L(j + 4, j + 3) * t2;
        for (Eigen::Index i = j + 4; i < rho; ++i) {
          const double* const l = &L(i + 1, j + 1);  // row-major: L(i + 1, j + 1 … j + 4)
          theta[i] = (((theta[i] - l[0] * t0) - l[1] * t1) - l[2] * t2) - l[3] * t3;
        }
      }
      for (; j + 1 < rho; ++j) {
        const double t = theta[j];
        for (Eigen::Index i = j + 1; i < rho; ++i) theta[i] -= L(i + 1, j + 1) * t;
      }
      theta_valid_ = true;
    }
    return theta_;
  }

  // Θ̂'z without touching the cache's validity rules. Throws InvalidArgument if z does not have one entry
  // per parameter.
  template <class Derived>
  double Predict(const Eigen::MatrixBase<Derived>& z) const {
    IDENT_REQUIRE(z.size() == theta_.size(), "Predict: z has {} entries; the model has {} parameters", z.size(),
                  theta_.size());
    return parameters().dot(z);
  }

  // V_z⁻¹ = L_z⁻¹ D_z⁻¹ L_z⁻ᵀ (allocates; O(ρ³)).
  Eigen::MatrixXd VzInverse() const {
    const Eigen::Index rho = theta_.size();
    const Eigen::MatrixXd Lz = V_.L().bottomRightCorner(rho, rho);
    const Eigen::MatrixXd Linv =
        Lz.template triangularView<Eigen::UnitLower>().solve(Eigen::MatrixXd::Identity(rho, rho));
    return Linv * V_.d().tail(rho).cwiseInverse().asDiagonal() * Linv.transpose();
  }

  // out = s·V_z⁻¹ without allocating: M = L_z⁻¹ by forward substitution into the strict lower
  // triangle of `out`, then out_ij = s Σ_{k≤i} M_ik M_jk / d_{z,k} (i ≤ j) into the upper triangle
  // and diagonal, then mirrored. ~ρ³/2 flops. `out` must be ρ x ρ (not checked here).
  template <class Derived>
  void ScaledVzInverse(double s, Eigen::MatrixBase<Derived>& out) const noexcept {
    const auto& L = V_.L();
    const auto& d = V_.d();
    const Eigen::Index rho = theta_.size();
    // M = L_z⁻¹, L_z(i,k) = L(i+1,k+1): M_ik = −L_z(i,k) − Σ_{k<j<i} L_z(i,j) M_jk  (i > k).
    for (Eigen::Index k = 0; k < rho; ++k)
      for (Eigen::Index i = k + 1; i < rho; ++i) {
        double m = -L(i + 1, k + 1);
        for (Eigen::Index j = k + 1; j < i; ++j) m -= L(i + 1, j + 1) * out(j, k);
        out(i, k) = m;
      }
    for (Eigen::Index i = 0; i < rho; ++i)
      for (Eigen::Index j = i; j < rho; ++j) {
        double c = (i == j ? 1.0 : out(j, i)) / d(i + 1);  // k = i: M_ii = 1
        for (Eigen::Index k = 0; k < i; ++k) c += out(i, k) * out(j, k) / d(k + 1);
        out(i, j) = s * c;
      }
    for (Eigen::Index i = 0; i < rho; ++i)
      for (Eigen::Index j = 0; j < i; ++j) out(i, j) = out(j, i);
  }

  Eigen::MatrixXd V() const { return V_.Reconstruct(); }

 private:
  // h = g = [y; z] (fixed-size copies when Dim is fixed).
  template <class Derived>
  void LoadSample(double y, const Eigen::MatrixBase<Derived>& z) noexcept {
    h_(0) = y;
    g_(0) = y;
    if constexpr (Dim == Eigen::Dynamic) {
      h_.tail(h_.size() - 1) = z;
      g_.tail(g_.size() - 1) = z;
    } else {
      h_.template tail<Dim - 1>() = z;
      g_.template tail<Dim - 1>() = z;
    }
  }

  double nu_ = 0;
  LdFactor<Dim> V_;
  Vector h_, g_;
  mutable ParamVector theta_;
  mutable bool theta_valid_ = false;
  Vector inv_d_, q_sum_;  // Prepare<true>: 1/d_i and Σ_{j≥i} g_j²/d_j, for PlanApply<true>
  bool kept_ = false;     // the last Prepare() kept the partial sums of its back substitution
};

}  // namespace ident
