// Square-root-free L'DL factorisation of a symmetric positive definite matrix, with the
// rank-one update used by every regression estimator in ident.
//
//   V = L' D L,   L unit lower triangular (stored by rows), D = diag(d_0 .. d_{n-1}) > 0.
//
// This is the Peterka/Kárný convention for the extended information matrix (index 0 = y):
// it is U D U' with U = L', or L D L' with the index order reversed [spec §6].
//
// Operations (n = size):
//   Factorize(V)          bottom-up L'DL of an SPD matrix, O(n^3)                     [spec §6]
//   ScaleD(s)             V <- s V, O(n)
//   RankOneUpdate(c, a)   V <- V + c a a' for c >= 0: Agee–Turner / Bierman U-D update,
//                         Gill–Golub–Murray–Saunders (1974) method C1; ~2n^2 flops, no square
//                         roots; all d_j stay positive. `a` is used as workspace.            [spec §6]
//   PlanUpdate(s, c, g)   the same update of V <- s V + c a a' in two phases, given g = L'^{-1} a
//   CommitUpdate(a)       (from SolveTransposed): the plan computes the new d and the multipliers
//                         b_j in O(n) without touching the factor (so a caller can check the result
//                         first, see ident/regression/internal/step_guard.h); the commit applies it, ~2n^2 flops.
//   PlanUpdateFromSums    the same plan from 1/d_j and Σ_{i≥j} g_i²/d_i formed beforehand (one division
//                         per j once c is known; the Kárný–Hangos estimators, whose c comes last)
//   OffDiagonalBound()    an upper bound on max |L_ij| (i != j): exact after Factorize/SetIdentity/
//                         RankOneUpdate (recomputed lazily, O(n^2)), grown by CommitUpdate in O(1)
//   SolveTransposed(h, g) solves L' g = h (back substitution, row-oriented), ~n^2/2 flops
//   Reconstruct()         V = L' D L (for tests and read-outs)
//
// Example:
//   ident::LdFactor<> f(V);                  // V SPD, n x n
//   Eigen::VectorXd a = h; f.RankOneUpdate(0.1, a);
//
// Allocation: none after construction for fixed `Dim`; for Eigen::Dynamic, none except in
// Factorize() when the size changes and in Reconstruct().
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Core>

#include "common/error.h"

namespace ident {

template <int Dim = Eigen::Dynamic>
class LdFactor {
 public:
  using Matrix = Eigen::Matrix<double, Dim, Dim, Eigen::RowMajor>;
  using Vector = Eigen::Matrix<double, Dim, 1>;

  // The n x n identity (L = I, d = 1).
  explicit LdFactor(int n = (Dim == Eigen::Dynamic ? 1 : Dim)) { SetIdentity(n); }

  // Factorises V; throws InvalidArgument if V is not square, not symmetric or not positive definite.
  explicit LdFactor(const Eigen::Ref<const Eigen::MatrixXd>& V) { Factorize(V); }

  // What PlanUpdate() found about the planned update (all O(n) by-products of the plan).
  struct Plan {
    double min_d = 0;      // min_j of the new d_j
    double max_d = 0;      // max_j of the new d_j
    double d_sum = 0;      // Σ new d_j: finite iff every new d_j is (barring overflow of the sum)
    double max_b = 0;      // max_j |b_j|: L_new[j, i] = L[j, i] + b_j a_i^(j)
    double g_abs_sum = 0;  // Σ|g_j|
  };

  int size() const { return static_cast<int>(d_.size()); }
  const Matrix& L() const { return L_; }
  const Vector& d() const { return d_; }

  void SetIdentity(int n) {
    IDENT_REQUIRE(n >= 1 && (Dim == Eigen::Dynamic || n == Dim), "LD factor size {} is invalid", n);
    L_.setIdentity(n, n);
    d_.setOnes(n);
    Workspace(n);
    l_bound_ = 0;
  }

  // L = I, d = `diagonal` (all entries must be positive: not checked). No allocation at the same size.
  template <class Derived>
  void SetDiagonal(const Eigen::MatrixBase<Derived>& diagonal) noexcept {
    L_.setIdentity();
    d_ = diagonal;
    l_bound_ = 0;
  }

  // Bottom-up L'DL [spec §6]: for j = n-1..0:
  //   d_j    = V_jj - sum_{k>j} d_k L[k,j]^2
  //   L[j,i] = (V_ij - sum_{k>j} d_k L[k,i] L[k,j]) / d_j     (i < j)
  void Factorize(const Eigen::Ref<const Eigen::MatrixXd>& V) {
    const Eigen::Index n = V.rows();
    IDENT_REQUIRE(n >= 1 && V.cols() == n, "matrix V is {}x{}; need a non-empty square matrix", V.rows(), V.cols());
    IDENT_REQUIRE(Dim == Eigen::Dynamic || n == Dim, "matrix V is {}x{}; need {}x{}", n, n, Dim, Dim);
    IDENT_REQUIRE(V.allFinite(), "matrix V has a non-finite entry");
    const double scale = V.cwiseAbs().maxCoeff();
    IDENT_REQUIRE(((V - V.transpose()).cwiseAbs().array() <= 1e-12 * scale).all(), "matrix V is not symmetric");
    Matrix& L = L_;
    L.setIdentity(n, n);
    d_.resize(n);
    for (Eigen::Index j = n - 1; j >= 0; --j) {
      double dj = V(j, j);
      for (Eigen::Index k = j + 1; k < n; ++k) dj -= d_(k) * L(k, j) * L(k, j);
      IDENT_REQUIRE(dj > 0 && std::isfinite(dj), "matrix V is not positive definite (pivot {} is {})", j, dj);
      d_(j) = dj;
      for (Eigen::Index i = 0; i < j; ++i) {
        double s = V(i, j);
        for (Eigen::Index k = j + 1; k < n; ++k) s -= d_(k) * L(k, i) * L(k, j);
        L(j, i) = s / dj;
      }
    }
    Workspace(static_cast<int>(n));
    l_bound_ = kStale;
  }

  // V <- s V (s > 0).
  void ScaleD(double s) { d_ *= s; }

  // Phase 1 of V <- s V + c a a' (s > 0, c > 0) given g = L'^{-1} a: the sweep of RankOneUpdate on
  // d only [spec §6], d'_j = s d_j, dn_j = d'_j + c_{j+1} g_j^2, b_j = c_{j+1} g_j / dn_j,
  // c_j = c_{j+1} d'_j / dn_j (c_n = c; g_j is the a_j of RankOneUpdate's sweep: its back substitution
  // is the one of SolveTransposed). In terms of u_j = 1/c_j this is a running sum of positive terms,
  //   u_j = u_{j+1} + g_j^2/d'_j,   dn_j = d'_j u_j / u_{j+1},   b_j = g_j / (d'_j u_j),
  // whose only dependency chain is one addition per j (the c-form chains a division per j, which
  // dominates small updates); if that overflows (u, 1/d' infinite: extreme scales) the c-form is used.
  // Stores the new d and b_j in a workspace; the factor is unchanged. O(n).
  template <class Derived>
  const Plan& PlanUpdate(double s, double c, const Eigen::MatrixBase<Derived>& g) noexcept {
    Plan p = PlanPrefixSum(s, c, g);
    if (!(std::isfinite(p.d_sum) && std::isfinite(p.max_b))) [[unlikely]]
      p = PlanChained(s, c, g);
    return Keep(p);
  }

  // The same plan when the caller already has, from the back substitution g = L'^{-1} a, the
  // reciprocals r_j = 1/d_j and the running sums Q_j = Σ_{i≥j} g_i² r_i (ExtendedInformation::Prepare
  // forms them for ξ, ξ_z [spec §6]). In terms of W_j = s + c Q_j (W_n = s; W_j = cs·u_j of the
  // prefix-sum form above) the sweep is
  //   dn_j = d_j W_j · (s/W_{j+1}),   b_j = c g_j r_j / W_j,
  // so once c is known only one FMA and one division per j remain, none of them chained (the
  // Kárný–Hangos weight c = β(t) is known only after ξ, ξ_z are: this keeps the divisions 1/d_j and
  // the running sum off the path from β to the update). Falls back to the c-form if that overflows.
  template <class DerivedG, class DerivedR, class DerivedQ>
  const Plan& PlanUpdateFromSums(double s, double c, const Eigen::MatrixBase<DerivedG>& g,
                                 const Eigen::MatrixBase<DerivedR>& inv_d,
                                 const Eigen::MatrixBase<DerivedQ>& q_sum) noexcept {
    const Eigen::Index n = d_.size();
    Plan p;
    p.min_d = std::numeric_limits<double>::infinity();
    sweep_end_ = 0;
    double ratio_next = 1;  // s/W_{j+1} (= 1 for j = n−1)
    for (Eigen::Index j = n - 1; j >= 0; --j) {
      const double w = s + c * q_sum(j);
      const double rw = 1 / w;
      const double gj = g(j);
      const double dn = d_(j) * w * ratio_next;
      const double b = c * gj * inv_d(j) * rw;
      ratio_next = s * rw;
      Record(p, j, dn, b, gj);
    }
    if (!(std::isfinite(p.d_sum) && std::isfinite(p.max_b))) [[unlikely]]
      p = PlanChained(s, c, g);
    return Keep(p);
  }

  // Phase 2: applies the last PlanUpdate(). `a` (size n, the a of the plan's g = L'^{-1} a) is
  // overwritten; `a_max` = max_i |a_i|. ~2n^2 flops:
  //   for j = n-1..1:  for i < j:  a_i -= a_j L[j,i];  L[j,i] += b_j a_i   (updated a_i)
  // The bound M on max|L| grows to GrownBound(M, a_max): the partial back substitution has
  // |a_i^(j)| ≤ |a_i| + Σ_k |g_k| M, so |L_new[j,i]| ≤ M + max|b_j| (max|a| + Σ|g| M).
  template <class Derived>
  void CommitUpdate(Eigen::MatrixBase<Derived>& a, double a_max) noexcept {
    const Eigen::Index n = d_.size();
    for (Eigen::Index j = n - 1; j >= std::max<Eigen::Index>(1, sweep_end_); --j) {
      const double aj = a(j);
      if (aj == 0.0) continue;
      const double b = b_(j);
      double* row = L_.data() + j * n;  // row-major: L[j, 0..j-1] contiguous
      for (Eigen::Index i = 0; i < j; ++i) {
        a(i) -= aj * row[i];
        row[i] += b * a(i);
      }
    }
    d_.swap(d_next_);
    if (l_bound_ == l_bound_) l_bound_ = GrownBound(l_bound_, a_max);  // (NaN: stale, recomputed on demand)
  }

  // SolveTransposed(g, g) that also keeps the partial sums a_i^(j) (g_i after row j, i < j), which
  // CommitUpdate(a) would form again, for CommitSolved().
  template <class DerivedG>
  void SolveTransposedKeep(Eigen::MatrixBase<DerivedG>& g_in) noexcept {
    const Eigen::Index n = d_.size();
    double* __restrict g = g_in.derived().data();
    double* __restrict kept = L_saved_.data();
#pragma GCC unroll 8
    for (Eigen::Index j = n - 1; j > 0; --j) {
      const double gj = g[j];
      if (gj == 0.0) continue;
      const double* __restrict row = L_.data() + j * n;
      double* __restrict row_kept = kept + j * n;
      for (Eigen::Index i = 0; i < j; ++i) {
        g[i] -= gj * row[i];
        row_kept[i] = g[i];
      }
    }
  }
  // CommitUpdate(a) from the partial sums kept by SolveTransposedKeep(a → g) before the last plan: the same
  // L, ~n² flops instead of ~2n². `g` = the solution it left.
  template <class DerivedG>
  void CommitSolved(const Eigen::MatrixBase<DerivedG>& g, double a_max) noexcept {
    const Eigen::Index n = d_.size();
    for (Eigen::Index j = n - 1; j >= std::max<Eigen::Index>(1, sweep_end_); --j) {
      if (g(j) == 0.0) continue;  // CommitUpdate's a_j at row j is g_j
      const double b = b_(j);
      double* __restrict row = L_.data() + j * n;
      const double* __restrict row_kept = L_saved_.data() + j * n;
      for (Eigen::Index i = 0; i < j; ++i) row[i] += b * row_kept[i];
    }
    d_.swap(d_next_);
    if (l_bound_ == l_bound_) l_bound_ = GrownBound(l_bound_, a_max);
  }

  // PlanUpdate(s, c, g = L'⁻¹a) and CommitUpdate(a) in one sweep, for a c known before g: the back
  // substitution, the prefix-sum plan and the rank-one update of L share the row loop (row j's plan needs
  // only g_j, final once rows > j are done). ~2n² flops where the two phases take ~3n² (the back
  // substitution is done once). L and d are updated in place, the old rows of L and the old d kept: the
  // caller judges the plan, then CommitFused() or RollbackFused() (the factor bit-identical to before).
  // Until then L and d are the new ones; OffDiagonalBound() still bounds the old L (GrownBound() the new one).
  // On entry `g` holds a; on return g = L'⁻¹a. `a` (not aliasing g) is read only if the prefix sum
  // overflows (then the c-form plan and its sweep are used, as PlanUpdate does). The same numbers as
  // the two phases, bit for bit.
  template <class DerivedG, class DerivedA>
  const Plan& PlanFused(double s, double c, Eigen::MatrixBase<DerivedG>& g_in,
                        const Eigen::MatrixBase<DerivedA>& a) noexcept {
    const Eigen::Index n = d_.size();
    if (!(l_bound_ == l_bound_)) l_bound_ = MaxAbsOffDiagonal();  // of the old L
    l_bound_before_ = l_bound_;
    double* __restrict L = L_.data();
    double* __restrict saved = L_saved_.data();
    double* __restrict g = g_in.derived().data();
    Plan p;
    p.min_d = std::numeric_limits<double>::infinity();
    sweep_end_ = 0;
    if (!(c == fused_c_)) fused_c_ = c, fused_inv_c_ = 1 / c;  // RLS's c = 1/ν settles under forgetting
    double u_next = fused_inv_c_, ru_next = c;                 // as PlanPrefixSum
#pragma GCC unroll 8
    for (Eigen::Index j = n - 1; j >= 0; --j) {
      const double dj = d_(j) * s;
      const double gj = g[j];
      double b = 0, dn = dj;
      double* __restrict row = L + j * n;
      double* __restrict row_saved = saved + j * n;
      if (gj != 0.0) {
        AgeeTurnerStep(dj, gj, u_next, ru_next, dn, b);
        for (Eigen::Index i = 0; i < j; ++i) {
          const double l = row[i];
          row_saved[i] = l;
          g[i] -= gj * l;
          row[i] = l + b * g[i];
        }
      } else {
        for (Eigen::Index i = 0; i < j; ++i) row_saved[i] = row[i];
      }
      // d in place too, the old d kept for RollbackFused(): the next step reads d_j straight from this store.
      d_next_(j) = d_(j);
      d_(j) = dn;
      Accumulate(p, dn, b, gj);
    }
    if (!(std::isfinite(p.d_sum) && std::isfinite(p.max_b))) [[unlikely]]
      p = FusedChained(s, c, g_in, a);
    return Keep(p);
  }

  // Keeps the last PlanFused() (its L and d are in place). `a_max` as for CommitUpdate.
  void CommitFused(double a_max) noexcept {
    if (l_bound_ == l_bound_) l_bound_ = GrownBound(l_bound_, a_max);
  }
  // Back to the factor before the last PlanFused(), bit for bit, committed or not.
  void RollbackFused() noexcept {
    const Eigen::Index n = d_.size();
    for (Eigen::Index j = 1; j < n; ++j) L_.row(j).head(j) = L_saved_.row(j).head(j);
    d_.swap(d_next_);
    l_bound_ = l_bound_before_;
  }

  // The bound on max|L| after committing the last plan, if it is M now (see CommitUpdate).
  double GrownBound(double M, double a_max) const noexcept {
    return (M + plan_.max_b * (a_max + plan_.g_abs_sum * M)) * kRoundingSlack;
  }

  // An upper bound on max_{i>j} |L_ij| (+inf or NaN if L is not finite); see the header comment.
  double OffDiagonalBound() const {
    if (!(l_bound_ == l_bound_)) l_bound_ = MaxAbsOffDiagonal();
    return l_bound_;
  }
  // Recomputes the bound exactly (O(n^2)), e.g. when the grown bound is too large to be useful.
  double TightenOffDiagonalBound() const { return l_bound_ = MaxAbsOffDiagonal(); }

  // V <- V + c a a', c >= 0. `a` (size n) is overwritten. Sweep from the last index [spec §6]:
  //   for j = n-1..0:  dn = d_j + c a_j^2;  b = c a_j / dn;  c = c d_j / dn;  d_j = dn
  //                    for i < j:  a_i -= a_j L[j,i];  L[j,i] += b a_i   (updated a_i)
  template <class Derived>
  void RankOneUpdate(double c, Eigen::MatrixBase<Derived>& a) {
    l_bound_ = kStale;
    const Eigen::Index n = d_.size();
    for (Eigen::Index j = n - 1; j >= 0 && c > 0; --j) {
      const double aj = a(j);
      if (aj == 0.0) continue;
      const double dn = d_(j) + c * aj * aj;
      const double b = c * aj / dn;
      c = c * d_(j) / dn;
      d_(j) = dn;
      double* row = L_.data() + j * n;  // row-major: L[j, 0..j-1] contiguous
      for (Eigen::Index i = 0; i < j; ++i) {
        a(i) -= aj * row[i];
        row[i] += b * a(i);
      }
    }
  }
  template <class Derived>
  void RankOneUpdate(double c, Eigen::MatrixBase<Derived>&& a) {
    RankOneUpdate(c, a);
  }

  // Solves L' g = h. `g` may alias `h`. Row-oriented back substitution: once g_j is final,
  // g[0..j-1] -= g_j L[j, 0..j-1].
  template <class DerivedH, class DerivedG>
  void SolveTransposed(const Eigen::MatrixBase<DerivedH>& h, Eigen::MatrixBase<DerivedG>& g) const {
    const Eigen::Index n = d_.size();
    if (static_cast<const void*>(&g) != static_cast<const void*>(&h)) g = h;
    for (Eigen::Index j = n - 1; j > 0; --j) {
      const double gj = g(j);
      if (gj == 0.0) continue;
      const double* row = L_.data() + j * n;
      for (Eigen::Index i = 0; i < j; ++i) g(i) -= gj * row[i];
    }
  }

  Eigen::MatrixXd Reconstruct() const {
    Eigen::MatrixXd Ld = L_;
    return Ld.transpose() * d_.asDiagonal() * Ld;
  }

 private:
  static constexpr double kStale = std::numeric_limits<double>::quiet_NaN();
  // Covers the rounding of the ~2n operations behind each L entry (relative 2^-52 each) many times over.
  static constexpr double kRoundingSlack = 1 + 0x1p-20;

  // Keeps `p` as the last plan and returns it. Field by field: a plan built in registers and copied whole
  // would go through memory with narrow stores and wide loads, which cannot be store-forwarded and stall
  // the step.
  const Plan& Keep(const Plan& p) noexcept {
    plan_.min_d = p.min_d;
    plan_.max_d = p.max_d;
    plan_.d_sum = p.d_sum;
    plan_.max_b = p.max_b;
    plan_.g_abs_sum = p.g_abs_sum;
    return plan_;
  }

  // One step j, for g_j ≠ 0, of the plan's recurrence (PlanPrefixSum): u_j = u_{j+1} + g_j²/d'_j,
  // dn_j = d'_j u_j / u_{j+1}, b_j = g_j / (d'_j u_j), with u_{j+1} and its reciprocal carried from step j+1.
  [[gnu::always_inline]] static void AgeeTurnerStep(double dj, double gj, double& u_next, double& ru_next, double& dn,
                                                    double& b) noexcept {
    const double w = 1 / dj;
    const double u = u_next + gj * gj * w;
    const double ru = 1 / u;
    dn = dj * u * ru_next;
    b = gj * w * ru;
    u_next = u, ru_next = ru;
  }

  // Stores the new d_j and b_j of a plan sweep and adds them to the plan's by-products.
  void Record(Plan& p, Eigen::Index j, double dn, double b, double gj) noexcept {
    d_next_(j) = dn;
    b_(j) = b;
    Accumulate(p, dn, b, gj);
  }
  static void Accumulate(Plan& p, double dn, double b, double gj) noexcept {
    p.min_d = std::min(p.min_d, dn);
    p.max_d = std::max(p.max_d, dn);
    p.d_sum += dn;
    p.max_b = std::max(p.max_b, std::abs(b));
    p.g_abs_sum += std::abs(gj);
  }

  void Workspace(int n) {
    d_next_.resize(n);
    b_.resize(n);
    a_work_.resize(n);
    L_saved_.resize(n, n);
  }

  template <class Derived>
  Plan PlanPrefixSum(double s, double c, const Eigen::MatrixBase<Derived>& g) noexcept {
    const Eigen::Index n = d_.size();
    Plan p;
    p.min_d = std::numeric_limits<double>::infinity();
    sweep_end_ = 0;
    double u_next = 1 / c, ru_next = c;  // u_{j+1}, 1/u_{j+1}
    for (Eigen::Index j = n - 1; j >= 0; --j) {
      const double dj = d_(j) * s;
      const double gj = g(j);
      double b = 0, dn = dj;
      if (gj != 0.0) AgeeTurnerStep(dj, gj, u_next, ru_next, dn, b);
      Record(p, j, dn, b, gj);
    }
    return p;
  }

  // The c-form of the same sweep (as RankOneUpdate), for scales where the prefix sum overflows
  // (rare: kept out of line, so that the common path's code stays small).
  template <class Derived>
  [[gnu::noinline, gnu::cold]] Plan PlanChained(double s, double c, const Eigen::MatrixBase<Derived>& g) noexcept {
    const Eigen::Index n = d_.size();
    Plan p;
    p.min_d = std::numeric_limits<double>::infinity();
    sweep_end_ = 0;
    for (Eigen::Index j = n - 1; j >= 0; --j) {
      const double dj = d_(j) * s;
      const double gj = g(j);
      double b = 0, dn = dj;
      if (c > 0 && gj != 0.0) {
        dn = dj + c * gj * gj;
        b = c * gj / dn;
        c = c * dj / dn;
      } else if (!(c > 0) && sweep_end_ == 0) {
        sweep_end_ = j + 1;  // rows < j+1 keep their L
      }
      Record(p, j, dn, b, gj);
    }
    return p;
  }

  // PlanFused's fallback: the c-form plan from the final g, and CommitUpdate's sweep on the old L (restored
  // from the kept rows) with a copy of a (rare: out of line).
  template <class DerivedG, class DerivedA>
  [[gnu::noinline, gnu::cold]] Plan FusedChained(double s, double c, const Eigen::MatrixBase<DerivedG>& g,
                                                 const Eigen::MatrixBase<DerivedA>& a) noexcept {
    d_.swap(d_next_);  // the old d back (PlanFused wrote the new one in place); PlanChained reads it
    const Plan p = PlanChained(s, c, g);
    d_.swap(d_next_);  // its new d in place, the old kept, as PlanFused leaves them
    const Eigen::Index n = d_.size();
    for (Eigen::Index j = 1; j < n; ++j) L_.row(j).head(j) = L_saved_.row(j).head(j);
    a_work_ = a;
    for (Eigen::Index j = n - 1; j >= std::max<Eigen::Index>(1, sweep_end_); --j) {
      const double aj = a_work_(j);
      if (aj == 0.0) continue;
      const double b = b_(j);
      double* row = L_.data() + j * n;
      for (Eigen::Index i = 0; i < j; ++i) {
        a_work_(i) -= aj * row[i];
        row[i] += b * a_work_(i);
      }
    }
    return p;
  }

  double MaxAbsOffDiagonal() const {
    const Eigen::Index n = d_.size();
    double m = 0;
    bool finite = true;
    for (Eigen::Index j = 1; j < n; ++j) {
      const auto row = L_.row(j).head(j);
      finite = finite && row.allFinite();
      m = std::max(m, row.cwiseAbs().maxCoeff());
    }
    return finite ? m : std::numeric_limits<double>::infinity();
  }

  Matrix L_;
  Matrix L_saved_;              // strict lower triangle: PlanFused's old rows of L, SolveTransposedKeep's partial sums
  Vector d_, d_next_;           // d_next_: a plan's new d, or PlanFused's old d
  Vector b_;                    // PlanUpdate -> CommitUpdate workspace
  Vector a_work_;               // PlanFused's fallback: a copy of a
  Eigen::Index sweep_end_ = 0;  // rows below this keep their L (the sweep's c reached 0)
  Plan plan_;                   // the last PlanUpdate()
  mutable double l_bound_ = kStale;                 // ≥ max |L_ij| off the diagonal; NaN = recompute
  double l_bound_before_ = kStale;                  // PlanFused: l_bound_ before the update
  double fused_c_ = kStale, fused_inv_c_ = kStale;  // PlanFused's last c and 1/c
};

}  // namespace ident
