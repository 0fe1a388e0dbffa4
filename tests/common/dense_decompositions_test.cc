// common/dense_decompositions.h: each function returns the decomposition Eigen's own class gives for the same
// matrix, bit for bit (the library's numbers do not depend on where a decomposition is constructed), and the
// read-outs satisfy their defining identities (A = LL', A·A⁻¹ = I, Q'Q = I, Av = λv).
#include "common/dense_decompositions.h"

#include <random>

#include <gtest/gtest.h>
#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <Eigen/QR>

namespace ident::dense {
namespace {

Eigen::MatrixXd Random(int rows, int cols, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g;
  Eigen::MatrixXd m(rows, cols);
  for (int j = 0; j < cols; ++j)
    for (int i = 0; i < rows; ++i) m(i, j) = g(rng);
  return m;
}

// Z'Z + I for a random 40 x n Z: symmetric positive definite, moderately conditioned.
Eigen::MatrixXd Spd(int n, unsigned seed) {
  const Eigen::MatrixXd z = Random(40, n, seed);
  return z.transpose() * z + Eigen::MatrixXd::Identity(n, n);
}

TEST(DenseDecompositions, CholeskyIsEigensBitForBitAndReconstructsA) {
  for (int n : {1, 3, 9, 40}) {
    const Eigen::MatrixXd a = Spd(n, 10 + n);
    const Eigen::LLT<Eigen::MatrixXd> ours = Llt(a), eigen(a);
    ASSERT_EQ(ours.info(), Eigen::Success);
    EXPECT_EQ(ours.matrixLLT(), eigen.matrixLLT()) << "n = " << n;
    const Eigen::MatrixXd l = ours.matrixL();
    EXPECT_LT((l * l.transpose() - a).norm(), 1e-12 * a.norm());
    const Eigen::MatrixXd inverse = Inverse(ours);
    EXPECT_EQ(inverse, eigen.solve(Eigen::MatrixXd::Identity(n, n)));
    EXPECT_LT((a * inverse - Eigen::MatrixXd::Identity(n, n)).norm(), 1e-10);
    EXPECT_LT((LowerTriangularInverse(ours.matrixLLT()) * l - Eigen::MatrixXd::Identity(n, n)).norm(), 1e-12);
  }
  Eigen::MatrixXd indefinite = Eigen::MatrixXd::Identity(3, 3);
  indefinite(2, 2) = -1;
  EXPECT_NE(Llt(indefinite).info(), Eigen::Success);
}

TEST(DenseDecompositions, LdltIsEigensBitForBitAndSolves) {
  const Eigen::MatrixXd a = Spd(12, 3);
  const Eigen::VectorXd b = Random(12, 1, 4);
  const Eigen::LDLT<Eigen::MatrixXd> ours = Ldlt(a), eigen(a);
  EXPECT_EQ(ours.matrixLDLT(), eigen.matrixLDLT());
  EXPECT_EQ(ours.solve(b), eigen.solve(b));
  EXPECT_LT((a * ours.solve(b) - b).norm(), 1e-12 * b.norm() * a.norm());
}

TEST(DenseDecompositions, FullPivotingLuFindsTheRankAndInverts) {
  const Eigen::MatrixXd a = Random(7, 7, 5);
  const Eigen::FullPivLU<Eigen::MatrixXd> ours = FullPivLu(a), eigen(a);
  EXPECT_EQ(ours.matrixLU(), eigen.matrixLU());
  ASSERT_TRUE(ours.isInvertible());
  EXPECT_EQ(Inverse(ours), eigen.inverse().eval());
  EXPECT_LT((a * Inverse(ours) - Eigen::MatrixXd::Identity(7, 7)).norm(), 1e-10);
  Eigen::MatrixXd singular = a;
  singular.col(6) = singular.col(0) - 2 * singular.col(3);  // rank 6
  EXPECT_EQ(FullPivLu(singular).rank(), 6);
}

TEST(DenseDecompositions, PivotedQrSolvesLeastSquaresAndKeepsQOrthonormal) {
  const Eigen::MatrixXd z = Random(30, 4, 6);
  const Eigen::VectorXd y = Random(30, 1, 7);
  const Eigen::VectorXd normal = (z.transpose() * z).llt().solve(z.transpose() * y);  // normal equations
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> cp = ColPivQr(z);
  EXPECT_EQ(cp.matrixQR(), Eigen::ColPivHouseholderQR<Eigen::MatrixXd>(z).matrixQR());
  EXPECT_EQ(cp.rank(), 4);
  EXPECT_LT((cp.solve(y) - normal).norm(), 1e-12 * normal.norm());
  const Eigen::MatrixXd q = LeadingQColumns(cp, 4);
  ASSERT_EQ(q.rows(), 30);
  ASSERT_EQ(q.cols(), 4);
  EXPECT_LT((q.transpose() * q - Eigen::MatrixXd::Identity(4, 4)).norm(), 1e-13);
  const Eigen::MatrixXd r = cp.matrixR().topLeftCorner(4, 4);
  const Eigen::MatrixXd r_inverse = UpperTriangularInverse(r);
  EXPECT_LT((r.triangularView<Eigen::Upper>() * r_inverse - Eigen::MatrixXd::Identity(4, 4)).norm(), 1e-12);
  // Z P = Q R: Q R P' reproduces Z.
  const Eigen::MatrixXd zp = q * r.triangularView<Eigen::Upper>();
  EXPECT_LT((zp * cp.colsPermutation().transpose() - z).norm(), 1e-12 * z.norm());
}

TEST(DenseDecompositions, SymmetricEigenSolversGiveEigenpairs) {
  const Eigen::MatrixXd a = Spd(6, 8);
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> ours = SymmetricEigen(a), eigen(a);
  EXPECT_EQ(ours.eigenvalues(), eigen.eigenvalues());
  EXPECT_EQ(ours.eigenvectors(), eigen.eigenvectors());
  const Eigen::MatrixXd v = ours.eigenvectors();
  EXPECT_LT((a * v - v * ours.eigenvalues().asDiagonal()).norm(), 1e-12 * a.norm());
  EXPECT_EQ(SymmetricEigen(a, Eigen::EigenvaluesOnly).eigenvalues(),
            Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(a, Eigen::EigenvaluesOnly).eigenvalues());

  const Eigen::Matrix2d b{{2.0, 1.0}, {1.0, 2.0}};  // eigenvalues 1 and 3
  const Eigen::Vector2d lambda = SymmetricEigen2x2(b).eigenvalues();
  EXPECT_NEAR(lambda(0), 1.0, 1e-15);
  EXPECT_NEAR(lambda(1), 3.0, 1e-15);

  // The tridiagonal solver on (diagonal, subdiagonal) against the full solver on the same matrix.
  const Eigen::VectorXd diagonal = Random(8, 1, 9), subdiagonal = Random(7, 1, 10);
  Eigen::MatrixXd t = diagonal.asDiagonal();
  for (int i = 0; i < 7; ++i) t(i + 1, i) = t(i, i + 1) = subdiagonal(i);
  const Eigen::VectorXd from_tridiagonal = SymmetricTridiagonalEigen(diagonal, subdiagonal).eigenvalues();
  EXPECT_LT((from_tridiagonal - SymmetricEigen(t).eigenvalues()).norm(), 1e-12 * t.norm());
}

}  // namespace
}  // namespace ident::dense
