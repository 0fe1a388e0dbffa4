#include "ident/block_tridiagonal.h"

#include <cmath>

#include "ident/common/error.h"

namespace ident {
namespace {

// Plain loops on column-major n x n blocks (ld = n): for the small blocks of state-space smoothing they
// are several times faster than Eigen's dynamic-size kernels.
inline double& At(double* A, int n, int i, int j) { return A[i + j * n]; }
inline double At(const double* A, int n, int i, int j) { return A[i + j * n]; }

// In-place Cholesky A = C C' (lower triangle of A becomes C). False if not positive definite.
bool CholeskyInPlace(double* A, int n) {
  for (int j = 0; j < n; ++j) {
    double d = At(A, n, j, j);
    for (int k = 0; k < j; ++k) d -= At(A, n, j, k) * At(A, n, j, k);
    if (!(d > 0) || !std::isfinite(d)) return false;
    const double c = std::sqrt(d);
    At(A, n, j, j) = c;
    for (int i = j + 1; i < n; ++i) {
      double s = At(A, n, i, j);
      for (int k = 0; k < j; ++k) s -= At(A, n, i, k) * At(A, n, j, k);
      At(A, n, i, j) = s / c;
    }
  }
  return true;
}

// b <- C^-1 b (C lower triangular).
inline void ForwardSolve(const double* C, int n, double* b) {
  for (int i = 0; i < n; ++i) {
    double s = b[i];
    for (int k = 0; k < i; ++k) s -= At(C, n, i, k) * b[k];
    b[i] = s / At(C, n, i, i);
  }
}

// b <- C^-T b.
inline void BackwardSolve(const double* C, int n, double* b) {
  for (int i = n - 1; i >= 0; --i) {
    double s = b[i];
    for (int k = i + 1; k < n; ++k) s -= At(C, n, k, i) * b[k];
    b[i] = s / At(C, n, i, i);
  }
}

}  // namespace

BlockTridiagonalCholesky::BlockTridiagonalCholesky(int block_size, int num_blocks)
    : n_(block_size), N_(num_blocks) {
  IDENT_REQUIRE(block_size >= 1 && num_blocks >= 1, "block-tridiagonal size {} x {} blocks is invalid", block_size,
                num_blocks);
  C_.resize(n_, static_cast<Eigen::Index>(n_) * N_);
  G_.resize(n_, static_cast<Eigen::Index>(n_) * N_);
  work_.resize(n_, n_);
}

bool BlockTridiagonalCholesky::Factorize(const Eigen::Ref<const Eigen::MatrixXd>& D,
                                         const Eigen::Ref<const Eigen::MatrixXd>& E) {
  IDENT_REQUIRE(D.rows() == n_ && D.cols() == C_.cols() && E.rows() == n_ && E.cols() == C_.cols(),
                "block-tridiagonal storage must be {} x {}", n_, C_.cols());
  const int n = n_;
  const Eigen::Index nn = static_cast<Eigen::Index>(n) * n;
  for (int t = 0; t < N_; ++t) {
    double* C = C_.data() + t * nn;
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) At(C, n, i, j) = D(i, static_cast<Eigen::Index>(t) * n + j);
    if (t > 0) {
      // G_t = E_t C_{t-1}^-T: row i of G solves C_{t-1} g = (row i of E_t)'.
      double* G = G_.data() + t * nn;
      const double* Cp = C_.data() + (t - 1) * nn;
      double* row = work_.data();
      for (int i = 0; i < n; ++i) {
        for (int j = 0; j < n; ++j) row[j] = E(i, static_cast<Eigen::Index>(t) * n + j);
        ForwardSolve(Cp, n, row);
        for (int j = 0; j < n; ++j) At(G, n, i, j) = row[j];
      }
      // C_t C_t' = D_t - G_t G_t' (lower triangle suffices)
      for (int j = 0; j < n; ++j)
        for (int i = j; i < n; ++i) {
          double s = 0;
          for (int k = 0; k < n; ++k) s += At(G, n, i, k) * At(G, n, j, k);
          At(C, n, i, j) -= s;
        }
    }
    if (!CholeskyInPlace(C, n)) return false;
  }
  return true;
}

void BlockTridiagonalCholesky::Solve(Eigen::Ref<Eigen::MatrixXd> b) const {
  IDENT_REQUIRE(b.rows() == n_ && b.cols() == N_, "right-hand side is {}x{}; need {}x{}", b.rows(), b.cols(), n_,
                N_);
  const int n = n_;
  const Eigen::Index nn = static_cast<Eigen::Index>(n) * n;
  for (int t = 0; t < N_; ++t) {
    double* bt = &b(0, t);
    if (t > 0) {
      const double* G = G_.data() + t * nn;
      const double* prev = &b(0, t - 1);
      for (int i = 0; i < n; ++i) {
        double s = 0;
        for (int k = 0; k < n; ++k) s += At(G, n, i, k) * prev[k];
        bt[i] -= s;
      }
    }
    ForwardSolve(C_.data() + t * nn, n, bt);
  }
  for (int t = N_ - 1; t >= 0; --t) {
    double* bt = &b(0, t);
    if (t + 1 < N_) {
      const double* G = G_.data() + (t + 1) * nn;
      const double* next = &b(0, t + 1);
      for (int i = 0; i < n; ++i) {
        double s = 0;
        for (int k = 0; k < n; ++k) s += At(G, n, k, i) * next[k];
        bt[i] -= s;
      }
    }
    BackwardSolve(C_.data() + t * nn, n, bt);
  }
}

}  // namespace ident
