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

#include <cmath>

#include <Eigen/Core>

#include "ident/common/error.h"

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

  int size() const { return static_cast<int>(d_.size()); }
  const Matrix& L() const { return L_; }
  const Vector& d() const { return d_; }

  void SetIdentity(int n) {
    IDENT_REQUIRE(n >= 1 && (Dim == Eigen::Dynamic || n == Dim), "LD factor size {} is invalid", n);
    L_.setIdentity(n, n);
    d_.setOnes(n);
  }

  // Bottom-up L'DL [spec §6]: for j = n-1..0:
  //   d_j    = V_jj - sum_{k>j} d_k L[k,j]^2
  //   L[j,i] = (V_ij - sum_{k>j} d_k L[k,i] L[k,j]) / d_j     (i < j)
  void Factorize(const Eigen::Ref<const Eigen::MatrixXd>& V) {
    const Eigen::Index n = V.rows();
    IDENT_REQUIRE(n >= 1 && V.cols() == n, "matrix V is {}x{}; need a non-empty square matrix", V.rows(),
                  V.cols());
    IDENT_REQUIRE(Dim == Eigen::Dynamic || n == Dim, "matrix V is {}x{}; need {}x{}", n, n, Dim, Dim);
    IDENT_REQUIRE(V.allFinite(), "matrix V has a non-finite entry");
    const double scale = V.cwiseAbs().maxCoeff();
    IDENT_REQUIRE(((V - V.transpose()).cwiseAbs().array() <= 1e-12 * scale).all(),
                  "matrix V is not symmetric");
    L_.setIdentity(n, n);
    d_.resize(n);
    for (Eigen::Index j = n - 1; j >= 0; --j) {
      double dj = V(j, j);
      for (Eigen::Index k = j + 1; k < n; ++k) dj -= d_(k) * L_(k, j) * L_(k, j);
      IDENT_REQUIRE(dj > 0 && std::isfinite(dj),
                    "matrix V is not positive definite (pivot {} is {})", j, dj);
      d_(j) = dj;
      for (Eigen::Index i = 0; i < j; ++i) {
        double s = V(i, j);
        for (Eigen::Index k = j + 1; k < n; ++k) s -= d_(k) * L_(k, i) * L_(k, j);
        L_(j, i) = s / dj;
      }
    }
  }

  // V <- s V (s > 0).
  void ScaleD(double s) { d_ *= s; }

  // V <- V + c a a', c >= 0. `a` (size n) is overwritten. Sweep from the last index [spec §6]:
  //   for j = n-1..0:  dn = d_j + c a_j^2;  b = c a_j / dn;  c = c d_j / dn;  d_j = dn
  //                    for i < j:  a_i -= a_j L[j,i];  L[j,i] += b a_i   (updated a_i)
  template <class Derived>
  void RankOneUpdate(double c, Eigen::MatrixBase<Derived>& a) {
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
  Matrix L_;
  Vector d_;
};

}  // namespace ident
