// Independent references from Eigen's dense solvers that tests compare ident's own algorithms with, compiled
// once here rather than in every test that needs them.
#pragma once

#include <Eigen/Core>

namespace ident::testing {

// argmin_θ |y − Zθ| by Householder QR (Eigen::HouseholderQR); Z of full column rank.
Eigen::VectorXd LeastSquaresByQr(const Eigen::MatrixXd& Z, const Eigen::VectorXd& y);

// The largest modulus of the roots of 1 + p1 q⁻¹ + … + p_n q⁻ⁿ: of the eigenvalues of its companion matrix
// (Eigen::EigenSolver, on the polynomial scaled to roots of order 1); 0 for n = 0.
double CompanionRootModulus(const double* p, int n);

}  // namespace ident::testing
