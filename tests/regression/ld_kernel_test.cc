// The benchmark's minimal LD kernel (bench/support/ld_kernel.h) is a correct RLS: after a few hundred
// updates with forgetting its Θ̂ equals the closed-form weighted least squares
// Θ̂ = Λ_z⁻¹Λ_zy, Λ = λ^T ν0V0 + Σ_k λ^{T−k} h_k h_k' (dense Cholesky), the covariance-form RLS oracle
// (tests/support/dense_rls.h) and ident's fixed-size RLS, to 1e-9.
#include "bench/support/ld_kernel.h"
#include "common/dense_decompositions.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <random>

#include <gtest/gtest.h>
#include <Eigen/Cholesky>
#include <Eigen/Core>

#include "ident/regression/rls.h"
#include "tests/support/dense_rls.h"

namespace ident {
namespace {

template <class A, class B>
double KernelRelativeDifference(const A& a, const B& b, int n) {
  double worst = 0;
  for (int i = 0; i < n; ++i) worst = std::max(worst, std::abs(a[i] - b[i]) / std::max(std::abs(b[i]), 1e-3));
  return worst;
}

template <int Rho>
void CheckKernel() {
  constexpr double lambda = 0.99, nu0 = 10, vy0 = 2, vz0 = 0.5;
  constexpr int kUpdates = 400;
  const RegressionPrior prior = RegressionPrior::Diagonal(Rho, nu0, vy0, vz0);
  std::array<double, Rho + 1> d0;
  d0.fill(nu0 * vz0);
  d0[0] = nu0 * vy0;
  bench::LdKernel<Rho> kernel(lambda, d0);
  BasicRecursiveLeastSquares<Rho> rls(Rho, {.forgetting = {.factor = lambda}, .prior = prior});
  BasicDenseRls<Rho> dense(prior, lambda);

  std::mt19937_64 rng(77 + Rho);
  std::normal_distribution<double> g;
  Eigen::Matrix<double, Rho, 1> theta;
  for (int i = 0; i < Rho; ++i) theta[i] = g(rng);
  Eigen::MatrixXd info = nu0 * prior.V0;  // Λ, accumulated densely
  for (int t = 0; t < kUpdates; ++t) {
    Eigen::Matrix<double, Rho, 1> z;
    for (int i = 0; i < Rho; ++i) z[i] = g(rng);
    const double y = theta.dot(z) + 0.3 * g(rng);
    kernel.Update(y, z.data());
    ASSERT_TRUE(rls.Update(y, z).updated());
    dense.Update(y, z);
    Eigen::VectorXd h(Rho + 1);
    h << y, z;
    info = lambda * info + h * h.transpose();
  }
  const Eigen::VectorXd closed_form = dense::Llt(info.bottomRightCorner(Rho, Rho)).solve(info.col(0).tail(Rho));
  const std::array<double, Rho> k = kernel.Parameters();
  const double vs_closed = KernelRelativeDifference(k, closed_form, Rho);
  const double vs_dense = KernelRelativeDifference(k, dense.parameters(), Rho);
  const double vs_rls = KernelRelativeDifference(k, rls.parameters(), Rho);
  EXPECT_LE(vs_closed, 1e-9) << "rho = " << Rho;
  EXPECT_LE(vs_dense, 1e-9) << "rho = " << Rho;
  EXPECT_LE(vs_rls, 1e-9) << "rho = " << Rho;
  // d_0 = the discounted residual sum: ν·D_y of the normalised RLS, and Λ_y − Λ_zy'Θ̂.
  const double residual = info(0, 0) - info.col(0).tail(Rho).dot(closed_form);
  EXPECT_NEAR(kernel.ResidualSum(), residual, 1e-9 * residual) << "rho = " << Rho;
  EXPECT_NEAR(kernel.ResidualSum(), rls.nu() * rls.Dy(), 1e-9 * residual) << "rho = " << Rho;
  // The estimate is informative (not the prior's zero): far closer to the true Θ than |Θ|.
  EXPECT_LT((closed_form - theta).norm(), 0.3 * theta.norm()) << "rho = " << Rho;
}

TEST(LdKernel, ThetaEqualsClosedFormDenseAndIdentRlsAfter400Updates) {
  CheckKernel<2>();
  CheckKernel<4>();
  CheckKernel<8>();
  CheckKernel<16>();
  CheckKernel<32>();
}

}  // namespace
}  // namespace ident
