#include "ident/block_tridiagonal.h"

#include <Eigen/Cholesky>

#include "ident/common/error.h"

namespace ident {

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
  for (int t = 0; t < N_; ++t) {
    auto C = C_.middleCols(t * n, n);
    C = D.middleCols(t * n, n);
    if (t > 0) {
      // G_t = E_t C_{t-1}^-T  <=>  G_t C_{t-1}' = E_t
      auto G = G_.middleCols(t * n, n);
      G = E.middleCols(t * n, n);
      C_.middleCols((t - 1) * n, n).triangularView<Eigen::Lower>().transpose().solveInPlace<Eigen::OnTheRight>(G);
      work_.noalias() = G * G.transpose();
      C -= work_;
    }
    Eigen::LLT<Eigen::Ref<Eigen::MatrixXd>> llt(C);  // in place: lower triangle of C becomes C_t
    if (llt.info() != Eigen::Success) return false;
    const double min_pivot = C.diagonal().minCoeff();
    if (!(min_pivot > 0) || !std::isfinite(min_pivot)) return false;
  }
  return true;
}

void BlockTridiagonalCholesky::Solve(Eigen::Ref<Eigen::MatrixXd> b) const {
  IDENT_REQUIRE(b.rows() == n_ && b.cols() == N_, "right-hand side is {}x{}; need {}x{}", b.rows(), b.cols(), n_,
                N_);
  const int n = n_;
  for (int t = 0; t < N_; ++t) {
    if (t > 0) b.col(t).noalias() -= G_.middleCols(t * n, n) * b.col(t - 1);
    C_.middleCols(t * n, n).triangularView<Eigen::Lower>().solveInPlace(b.col(t));
  }
  for (int t = N_ - 1; t >= 0; --t) {
    if (t + 1 < N_) b.col(t).noalias() -= G_.middleCols((t + 1) * n, n).transpose() * b.col(t + 1);
    C_.middleCols(t * n, n).triangularView<Eigen::Lower>().transpose().solveInPlace(b.col(t));
  }
}

}  // namespace ident
