// RLS with the flat prior against batch least squares (Eigen's Householder QR on the stacked
// regressors) on the bundled real records, with the regressor matrix built here by direct indexing
// (independently of models::ArxRegressor), and against the datasets README's numpy baselines.
#include <cmath>
#include <cstdio>

#include <gtest/gtest.h>
#include <Eigen/LU>

#include "ident/regression/rls.h"
#include "tests/support/reference_linear_algebra.h"
#include "tests/support/test_data.h"

namespace ident {
namespace {

struct ArxCase {
  const char* file;
  int na, nb, nk;
  std::vector<double> readme_theta;  // datasets/README.md "Our baseline" (printed precision)
  double readme_tolerance;           // half a unit of the last printed digit, relative
};

// Estimation part (first half), estimation-part means removed from u and y.
void BuildRegression(const ArxCase& c, Eigen::MatrixXd& Z, Eigen::VectorXd& Y) {
  std::vector<std::string> names;
  const Eigen::MatrixXd data = testing::ReadCsvMatrix(testing::DatasetPath(c.file), &names);
  const int n = static_cast<int>(data.rows()) / 2;
  Eigen::VectorXd u = data.col(1).head(n), y = data.col(2).head(n);
  u.array() -= u.mean();
  y.array() -= y.mean();
  const int t0 = std::max(c.na, c.nk + c.nb - 1);
  Z.resize(n - t0, c.na + c.nb);
  Y.resize(n - t0);
  for (int t = t0; t < n; ++t) {
    for (int k = 1; k <= c.na; ++k) Z(t - t0, k - 1) = -y(t - k);
    for (int k = 0; k < c.nb; ++k) Z(t - t0, c.na + k) = u(t - c.nk - k);
    Y(t - t0) = y(t);
  }
}

class BatchLeastSquares : public ::testing::TestWithParam<ArxCase> {};

TEST_P(BatchLeastSquares, FlatPriorRlsEqualsQrSolutionAndReadmeBaseline) {
  const ArxCase& c = GetParam();
  Eigen::MatrixXd Z;
  Eigen::VectorXd Y;
  BuildRegression(c, Z, Y);
  const Eigen::VectorXd batch = testing::LeastSquaresByQr(Z, Y);
  RecursiveLeastSquares rls(static_cast<int>(Z.cols()));
  for (Eigen::Index t = 0; t < Z.rows(); ++t) ASSERT_TRUE(rls.Update(Y(t), Z.row(t).transpose()).updated());
  const Eigen::VectorXd theta = rls.parameters();
  const double max_rel = ((theta - batch).cwiseAbs().array() / batch.cwiseAbs().array()).maxCoeff();
  std::printf("[ measured ] %s: max relative difference RLS vs QR = %.3g\n", c.file, max_rel);
  EXPECT_LE(max_rel, 1e-8) << c.file << ": RLS " << theta.transpose() << " vs QR " << batch.transpose();
  // Residual variance: RSS/(N − ρ) from the batch solution.
  const double s2 = (Y - Z * batch).squaredNorm() / static_cast<double>(Z.rows() - Z.cols());
  EXPECT_NEAR(rls.noise_variance(), s2, 1e-8 * s2);
  // Covariance s²(Z'Z)⁻¹.
  const Eigen::MatrixXd cov = s2 * (Z.transpose() * Z).inverse();
  EXPECT_LT((rls.covariance() - cov).norm(), 1e-7 * cov.norm());
  for (std::size_t i = 0; i < c.readme_theta.size(); ++i)
    EXPECT_NEAR(theta(i), c.readme_theta[i], c.readme_tolerance * std::abs(c.readme_theta[i]))
        << c.file << " theta(" << i << ")";
}

// The same record in small units (u and y × 1e-5): RegressionPrior::Flat(mean squares) keeps RLS on the QR
// solution, while the unit-free flat prior (information 1e-12·I against Z'Z ~ 1e-8) pulls θ̂ off it.
TEST(BatchLeastSquaresSmallUnits, ScaledFlatPriorKeepsRlsOnTheQrSolution) {
  Eigen::MatrixXd Z;
  Eigen::VectorXd Y;
  BuildRegression(ArxCase{"dryer.csv", 2, 2, 3, {}, 0}, Z, Y);
  Z *= 1e-5;
  Y *= 1e-5;
  const Eigen::VectorXd batch = testing::LeastSquaresByQr(Z, Y);
  Eigen::VectorXd mean_squares(Z.cols() + 1);
  mean_squares(0) = Y.squaredNorm() / static_cast<double>(Y.size());
  mean_squares.tail(Z.cols()) = Z.colwise().squaredNorm().transpose() / static_cast<double>(Z.rows());
  auto max_relative_error = [&](const RlsOptions& options) {
    RecursiveLeastSquares rls(static_cast<int>(Z.cols()), options);
    for (Eigen::Index t = 0; t < Z.rows(); ++t) EXPECT_TRUE(rls.Update(Y(t), Z.row(t).transpose()).updated());
    return ((rls.parameters() - batch).cwiseAbs().array() / batch.cwiseAbs().array()).maxCoeff();
  };
  RlsOptions scaled;
  scaled.prior = RegressionPrior::Flat(mean_squares);
  const double with_scaled = max_relative_error(scaled), with_unit = max_relative_error({});
  std::printf("[ measured ] dryer x 1e-5: RLS vs QR, scaled flat prior %.3g, unit flat prior %.3g\n", with_scaled,
              with_unit);
  EXPECT_LE(with_scaled, 1e-8);
  EXPECT_GE(with_unit, 1e-6);  // the bias the scaled prior removes
}

TEST(BatchLeastSquaresSmallUnits, ScaledFlatPriorRefusesMeanSquaresOutOfRange) {
  EXPECT_THROW(RegressionPrior::Flat(Eigen::Vector3d(1, 1e-300, 1)), InvalidArgument);
  EXPECT_THROW(RegressionPrior::Flat(Eigen::Vector3d(1, 0, 1)), InvalidArgument);
  EXPECT_THROW(RegressionPrior::Flat(Eigen::Vector3d(1, std::nan(""), 1)), InvalidArgument);
  const RegressionPrior p = RegressionPrior::Flat(Eigen::Vector3d(4, 2e-10, 3e5));
  EXPECT_EQ(p.nu0, 1e-12);
  EXPECT_EQ(p.V0, Eigen::Vector3d(4, 2e-10, 3e5).asDiagonal().toDenseMatrix());
}

INSTANTIATE_TEST_SUITE_P(
    RealRecords, BatchLeastSquares,
    ::testing::Values(ArxCase{"dryer.csv", 2, 2, 3, {-1.27654, 0.396711, 0.0651903, 0.0451792}, 5e-6},
                      ArxCase{"gas_furnace.csv", 2, 2, 3, {-1.071, 0.286356, -0.882687, 0.185909}, 5e-4},
                      ArxCase{"exchanger.csv", 2, 2, 1, {-1.19472, 0.242377, -0.0427583, -0.398151}, 5e-6}),
    [](const auto& info) { return std::string(info.param.file).substr(0, 5); });

}  // namespace
}  // namespace ident
