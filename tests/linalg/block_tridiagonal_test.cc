// Block-tridiagonal Cholesky (ident/linalg/block_tridiagonal.h) against a dense LLT solve of the same matrix.
#include "ident/linalg/block_tridiagonal.h"
#include "common/dense_decompositions.h"

#include <random>

#include <gtest/gtest.h>
#include <Eigen/Cholesky>

namespace ident {
namespace {

TEST(BlockTridiagonalCholesky, SolveMatchesDenseCholesky) {
  std::mt19937 rng(9);
  std::normal_distribution<double> N(0, 1);
  for (int n : {1, 2, 3, 4, 5})
    for (int blocks : {1, 2, 7}) {
      // A = J'J + I with J block lower bidiagonal: SPD and block tridiagonal.
      const int size = n * blocks;
      Eigen::MatrixXd J = Eigen::MatrixXd::Zero(size, size);
      for (int t = 0; t < blocks; ++t)
        for (int i = 0; i < n; ++i)
          for (int j = 0; j < n; ++j) {
            J(t * n + i, t * n + j) = N(rng);
            if (t > 0) J(t * n + i, (t - 1) * n + j) = N(rng);
          }
      const Eigen::MatrixXd A = J.transpose() * J + Eigen::MatrixXd::Identity(size, size);
      Eigen::MatrixXd D(n, size), E = Eigen::MatrixXd::Zero(n, size);
      for (int t = 0; t < blocks; ++t) {
        D.middleCols(t * n, n) = A.block(t * n, t * n, n, n);
        if (t > 0) E.middleCols(t * n, n) = A.block(t * n, (t - 1) * n, n, n);
      }
      BlockTridiagonalCholesky chol(n, blocks);
      ASSERT_TRUE(chol.Factorize(D, E));
      Eigen::VectorXd b(size);
      for (int i = 0; i < size; ++i) b(i) = N(rng);
      Eigen::MatrixXd x = Eigen::Map<Eigen::MatrixXd>(b.data(), n, blocks);
      chol.Solve(x);
      const Eigen::VectorXd dense = ident::dense::Llt(A).solve(b);
      EXPECT_LT((Eigen::Map<Eigen::VectorXd>(x.data(), size) - dense).cwiseAbs().maxCoeff(), 1e-10)
          << "n " << n << " blocks " << blocks;
    }
}

TEST(BlockTridiagonalCholesky, ReportsAMatrixThatIsNotPositiveDefinite) {
  Eigen::MatrixXd D(1, 2), E(1, 2);
  D << 1, 1;
  E << 0, 2;  // [[1, 2], [2, 1]] is indefinite
  BlockTridiagonalCholesky chol(1, 2);
  EXPECT_FALSE(chol.Factorize(D, E));
}

}  // namespace
}  // namespace ident
