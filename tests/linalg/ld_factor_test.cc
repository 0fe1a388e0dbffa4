#include "ident/linalg/ld_factor.h"

#include <random>

#include <Eigen/Cholesky>

#include <gtest/gtest.h>

#include "common/dense_decompositions.h"
#include "common/error.h"

namespace ident {
namespace {

Eigen::MatrixXd RandomSpd(int n, std::mt19937& rng) {
  std::normal_distribution<double> N;
  Eigen::MatrixXd A(n, n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) A(i, j) = N(rng);
  return A * A.transpose() + 0.1 * Eigen::MatrixXd::Identity(n, n);
}

TEST(LdFactor, FactorizeReconstructsTheMatrix) {
  std::mt19937 rng(1);
  for (int n : {1, 2, 5, 12}) {
    const Eigen::MatrixXd V = RandomSpd(n, rng);
    LdFactor<> f(V);
    EXPECT_LT((f.Reconstruct() - V).norm(), 1e-12 * V.norm()) << "n=" << n;
    EXPECT_GT(f.d().minCoeff(), 0);
    // L is unit lower triangular.
    EXPECT_TRUE(f.L().diagonal().isOnes());
    EXPECT_EQ(Eigen::MatrixXd(f.L()).triangularView<Eigen::StrictlyUpper>().toDenseMatrix().norm(), 0);
  }
}

TEST(LdFactor, RankOneUpdateMatchesDenseUpdate) {
  std::mt19937 rng(2);
  std::normal_distribution<double> N;
  for (int n : {1, 3, 8}) {
    Eigen::MatrixXd V = RandomSpd(n, rng);
    LdFactor<> f(V);
    for (int step = 0; step < 50; ++step) {
      Eigen::VectorXd a(n);
      for (int i = 0; i < n; ++i) a(i) = (i % 3 == 1 && step % 2) ? 0.0 : N(rng);
      const double c = std::abs(N(rng));
      V += c * a * a.transpose();
      Eigen::VectorXd work = a;
      f.RankOneUpdate(c, work);
    }
    EXPECT_LT((f.Reconstruct() - V).norm(), 1e-11 * V.norm()) << "n=" << n;
  }
}

TEST(LdFactor, SolveTransposedSolvesLtg) {
  std::mt19937 rng(3);
  const Eigen::MatrixXd V = RandomSpd(6, rng);
  LdFactor<> f(V);
  Eigen::VectorXd h = Eigen::VectorXd::LinSpaced(6, -1, 2), g(6);
  f.SolveTransposed(h, g);
  EXPECT_LT((Eigen::MatrixXd(f.L()).transpose() * g - h).norm(), 1e-13);
  // h' V^{-1} h = g' D^{-1} g.
  EXPECT_NEAR(h.dot(dense::Ldlt(V).solve(h)), g.dot(f.d().cwiseInverse().asDiagonal() * g), 1e-10);
}

TEST(LdFactor, FixedSizeAgreesWithDynamic) {
  std::mt19937 rng(4);
  const Eigen::MatrixXd V = RandomSpd(4, rng);
  LdFactor<> dyn(V);
  LdFactor<4> fix(V);
  Eigen::Vector4d a(1, -2, 0.5, 3);
  Eigen::VectorXd ad = a;
  fix.RankOneUpdate(0.7, a);
  dyn.RankOneUpdate(0.7, ad);
  EXPECT_LT((fix.Reconstruct() - dyn.Reconstruct()).norm(), 1e-14 * V.norm());
}

TEST(LdFactor, RejectsMatricesThatAreNotPositiveDefinite) {
  Eigen::Matrix2d V;
  V << 1, 2, 2, 1;
  EXPECT_THROW(LdFactor<>{V}, InvalidArgument);
  V << 1, 0.5, 0.4, 1;
  EXPECT_THROW(LdFactor<>{V}, InvalidArgument);  // not symmetric
  V << 1, 0, 0, std::nan("");
  EXPECT_THROW(LdFactor<>{V}, InvalidArgument);
}

}  // namespace
}  // namespace ident
