#include "ident/linalg/block_tridiagonal.h"

#include <cmath>

#include "common/error.h"

namespace ident {
namespace {

// Plain loops on column-major n x n blocks (ld = n). kN > 0 fixes the block size at compile time
// (n = 1..4: the loops unroll); kN = 0 is the run-time-size fallback.
template <int kN>
inline int Size(int n) {
  return kN > 0 ? kN : n;
}
inline double& At(double* A, int n, int i, int j) { return A[i + j * n]; }
inline double At(const double* A, int n, int i, int j) { return A[i + j * n]; }

// In-place Cholesky A = C C': the strict lower triangle of A becomes C's, the diagonal holds 1 / C_jj
// (the solves multiply instead of divide: the recursions over t are latency-bound). False if not
// positive definite.
template <int kN>
inline bool CholeskyInPlace(double* A, int n_runtime) {
  const int n = Size<kN>(n_runtime);
  for (int j = 0; j < n; ++j) {
    double d = At(A, n, j, j);
    for (int k = 0; k < j; ++k) d -= At(A, n, j, k) * At(A, n, j, k);
    if (!(d > 0) || !std::isfinite(d)) return false;
    const double inv = 1.0 / std::sqrt(d);
    At(A, n, j, j) = inv;
    for (int i = j + 1; i < n; ++i) {
      double s = At(A, n, i, j);
      for (int k = 0; k < j; ++k) s -= At(A, n, i, k) * At(A, n, j, k);
      At(A, n, i, j) = s * inv;
    }
  }
  return true;
}

// b <- C^-1 b (C lower triangular, diagonal stored inverted).
template <int kN>
inline void ForwardSolve(const double* C, int n_runtime, double* b) {
  const int n = Size<kN>(n_runtime);
  for (int i = 0; i < n; ++i) {
    double s = b[i];
    for (int k = 0; k < i; ++k) s -= At(C, n, i, k) * b[k];
    b[i] = s * At(C, n, i, i);
  }
}

// b <- C^-T b.
template <int kN>
inline void BackwardSolve(const double* C, int n_runtime, double* b) {
  const int n = Size<kN>(n_runtime);
  for (int i = n - 1; i >= 0; --i) {
    double s = b[i];
    for (int k = i + 1; k < n; ++k) s -= At(C, n, k, i) * b[k];
    b[i] = s * At(C, n, i, i);
  }
}

// Block Cholesky of the header: C_0 C_0' = D_0;  G_t = E_t C_{t-1}^-T;  C_t C_t' = D_t - G_t G_t'.
template <int kN>
bool FactorizeBlocks(const double* D, const double* E, int n_runtime, int N, double* C_all, double* G_all,
                     double* row) {
  const int n = Size<kN>(n_runtime);
  const Eigen::Index nn = static_cast<Eigen::Index>(n) * n;
  for (int t = 0; t < N; ++t) {
    double* C = C_all + t * nn;
    const double* Dt = D + t * nn;
    for (int i = 0; i < n * n; ++i) C[i] = Dt[i];
    if (t > 0) {
      // G_t = E_t C_{t-1}^-T: row i of G solves C_{t-1} g = (row i of E_t)'.
      double* G = G_all + t * nn;
      const double* Et = E + t * nn;
      const double* Cp = C_all + (t - 1) * nn;
      for (int i = 0; i < n; ++i) {
        for (int j = 0; j < n; ++j) row[j] = At(Et, n, i, j);
        ForwardSolve<kN>(Cp, n, row);
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
    if (!CholeskyInPlace<kN>(C, n)) return false;
  }
  return true;
}

// Forward  y_t = C_t^-1 (b_t - G_t y_{t-1}),  backward  x_t = C_t^-T (y_t - G_{t+1}' x_{t+1}).
template <int kN>
void SolveBlocks(const double* C_all, const double* G_all, int n_runtime, int N, double* b) {
  const int n = Size<kN>(n_runtime);
  const Eigen::Index nn = static_cast<Eigen::Index>(n) * n;
  for (int t = 0; t < N; ++t) {
    double* bt = b + static_cast<Eigen::Index>(t) * n;
    if (t > 0) {
      const double* G = G_all + t * nn;
      const double* prev = bt - n;
      for (int i = 0; i < n; ++i) {
        double s = 0;
        for (int k = 0; k < n; ++k) s += At(G, n, i, k) * prev[k];
        bt[i] -= s;
      }
    }
    ForwardSolve<kN>(C_all + t * nn, n, bt);
  }
  for (int t = N - 1; t >= 0; --t) {
    double* bt = b + static_cast<Eigen::Index>(t) * n;
    if (t + 1 < N) {
      const double* G = G_all + (t + 1) * nn;
      const double* next = bt + n;
      for (int i = 0; i < n; ++i) {
        double s = 0;
        for (int k = 0; k < n; ++k) s += At(G, n, k, i) * next[k];
        bt[i] -= s;
      }
    }
    BackwardSolve<kN>(C_all + t * nn, n, bt);
  }
}

}  // namespace

bool FactorizeBlockTridiagonal(int n, int N, const double* D, const double* E, double* C, double* G, double* work) {
  switch (n) {  // fixed-size kernels for small blocks, run-time size beyond
    case 1:
      return FactorizeBlocks<1>(D, E, n, N, C, G, work);
    case 2:
      return FactorizeBlocks<2>(D, E, n, N, C, G, work);
    case 3:
      return FactorizeBlocks<3>(D, E, n, N, C, G, work);
    case 4:
      return FactorizeBlocks<4>(D, E, n, N, C, G, work);
    default:
      return FactorizeBlocks<0>(D, E, n, N, C, G, work);
  }
}

void SolveBlockTridiagonal(int n, int N, const double* C, const double* G, double* b) {
  switch (n) {
    case 1:
      return SolveBlocks<1>(C, G, n, N, b);
    case 2:
      return SolveBlocks<2>(C, G, n, N, b);
    case 3:
      return SolveBlocks<3>(C, G, n, N, b);
    case 4:
      return SolveBlocks<4>(C, G, n, N, b);
    default:
      return SolveBlocks<0>(C, G, n, N, b);
  }
}

BlockTridiagonalCholesky::BlockTridiagonalCholesky(int block_size, int num_blocks) : n_(block_size), N_(num_blocks) {
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
  IDENT_REQUIRE(D.outerStride() == n_ && E.outerStride() == n_, "block-tridiagonal storage must be contiguous");
  return FactorizeBlockTridiagonal(n_, N_, D.data(), E.data(), C_.data(), G_.data(), work_.data());
}

void BlockTridiagonalCholesky::Solve(Eigen::Ref<Eigen::MatrixXd> b) const {
  IDENT_REQUIRE(b.rows() == n_ && b.cols() == N_ && b.outerStride() == n_, "right-hand side is {}x{}; need {}x{}",
                b.rows(), b.cols(), n_, N_);
  SolveBlockTridiagonal(n_, N_, C_.data(), G_.data(), b.data());
}

}  // namespace ident
