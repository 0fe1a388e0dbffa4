// Cholesky factorisation and solve of a symmetric positive definite block-tridiagonal matrix.
//
//       | D_0  E_1'                |
//   A = | E_1  D_1  E_2'           |      N blocks of size n x n (D_t symmetric), O(N n^3) flops.
//       |      E_2  D_2  ...       |
//       |           ...  E_{N-1} D_{N-1} |
//
// Block Cholesky A = L L' with L block lower bidiagonal (diagonal blocks C_t lower triangular, sub-
// diagonal blocks G_t):  C_0 C_0' = D_0;  G_t = E_t C_{t-1}^-T;  C_t C_t' = D_t - G_t G_t'.
// Solve: forward  y_t = C_t^-1 (b_t - G_t y_{t-1}),  backward  x_t = C_t^-T (y_t - G_{t+1}' x_{t+1}).
// This is the kernel of each Newton step of the interior-point MAP smoother (Aravkin, Burke &
// Pillonetto, JMLR 14 (2013), sec. 4: "each iteration is a block tridiagonal solve").
//
// Storage: D (n x nN) holds D_t in columns [t n, (t+1) n); E (n x nN) holds E_t in the same columns
// (E_0 unused). Vectors are n x N matrices, column t = block t.
//
// Example:
//   ident::BlockTridiagonalCholesky chol(n, N);
//   if (!chol.Factorize(D, E)) { /* not positive definite */ }
//   chol.Solve(b);   // b (n x N) is overwritten by A^-1 b
//
// Allocation: none after construction. FactorizeBlockTridiagonal / SolveBlockTridiagonal do the same on
// caller-owned storage (for solvers that keep all work arrays in one block, ident/linalg/work_arena.h).
#pragma once

#include <Eigen/Core>

namespace ident {

class BlockTridiagonalCholesky {
 public:
  BlockTridiagonalCholesky(int block_size, int num_blocks);

  int block_size() const { return n_; }
  int num_blocks() const { return N_; }

  // Returns false (and leaves the factor unusable) if A is not numerically positive definite.
  bool Factorize(const Eigen::Ref<const Eigen::MatrixXd>& D, const Eigen::Ref<const Eigen::MatrixXd>& E);
  // b <- A^-1 b for an n x N right-hand side (after a successful Factorize).
  void Solve(Eigen::Ref<Eigen::MatrixXd> b) const;

 private:
  int n_, N_;
  Eigen::MatrixXd C_;  // n x nN, lower-triangular diagonal factors (their diagonals stored inverted)
  Eigen::MatrixXd G_;  // n x nN, sub-diagonal factors (block 0 unused)
  Eigen::MatrixXd work_;
};

// The factorisation above on raw column-major storage: D, E, C, G are n x (n N) (block t in columns
// [t n, (t+1) n), E_0 and G_0 unused), `work` holds n doubles. Returns false if A is not numerically
// positive definite. No allocation, no argument checks (the class above checks).
bool FactorizeBlockTridiagonal(int n, int N, const double* D, const double* E, double* C, double* G, double* work);
// b (n x N) <- A^-1 b with the factor (C, G) of FactorizeBlockTridiagonal.
void SolveBlockTridiagonal(int n, int N, const double* C, const double* G, double* b);

}  // namespace ident
