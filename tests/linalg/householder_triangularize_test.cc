// TriangularizeInPlace (the array-form filters' QR step) against the defining property of the R factor:
// A = Q R with Q orthogonal means R'R = A'A, R upper triangular; checked for the fixed sizes the Kalman filter
// uses and a dynamic tall matrix, with a random A (seeded).
#include "ident/linalg/householder_triangularize.h"

#include <random>

#include <gtest/gtest.h>

namespace ident {
namespace {

template <typename Matrix>
void ExpectRFactorOf(Matrix a) {
  const Matrix original = a;
  Eigen::VectorXd workspace(a.cols());
  TriangularizeInPlace(a, workspace);
  const Eigen::MatrixXd r = a.topRows(a.cols()).template triangularView<Eigen::Upper>();
  const Eigen::MatrixXd gram = original.transpose() * original;
  EXPECT_LT((r.transpose() * r - gram).norm(), 1e-13 * gram.norm());
  // R's diagonal carries the column norms in the Cholesky sense: |R_11| = ‖A e_1‖.
  EXPECT_NEAR(std::abs(r(0, 0)), original.col(0).norm(), 1e-14 * original.col(0).norm());
}

TEST(TriangularizeInPlace, RIsTheCholeskyFactorOfTheGramMatrix) {
  std::mt19937 rng(7);
  std::normal_distribution<double> normal;
  for (int trial = 0; trial < 20; ++trial) {
    ExpectRFactorOf(Eigen::Matrix<double, 4, 2>(Eigen::Matrix<double, 4, 2>::NullaryExpr([&] { return normal(rng); })));
    ExpectRFactorOf(Eigen::Matrix3d(Eigen::Matrix3d::NullaryExpr([&] { return normal(rng); })));
    ExpectRFactorOf(Eigen::MatrixXd(Eigen::MatrixXd::NullaryExpr(9, 5, [&] { return normal(rng); })));
  }
}

TEST(TriangularizeInPlace, ZeroColumnsAndASingleRowAreLeftConsistent) {
  Eigen::Matrix3d a = Eigen::Matrix3d::Zero();
  a(2, 2) = -2;  // the first two columns are zero: no reflection is needed there
  Eigen::Vector3d workspace;
  TriangularizeInPlace(a, workspace);
  EXPECT_DOUBLE_EQ(a(0, 0), 0);
  EXPECT_DOUBLE_EQ(std::abs(a(2, 2)), 2);
  Eigen::RowVector3d row(3, 0, 4);
  TriangularizeInPlace(row, workspace);
  EXPECT_DOUBLE_EQ(row(0), 3);  // one row: nothing to annihilate
}

}  // namespace
}  // namespace ident
