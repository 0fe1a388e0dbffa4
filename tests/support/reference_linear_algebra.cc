#include "tests/support/reference_linear_algebra.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Eigenvalues>
#include <Eigen/QR>

namespace ident::testing {

Eigen::VectorXd LeastSquaresByQr(const Eigen::MatrixXd& Z, const Eigen::VectorXd& y) {
  return Eigen::HouseholderQR<Eigen::MatrixXd>(Z).solve(y);
}

double CompanionRootModulus(const double* p, int n) {
  if (n == 0) return 0;
  // The roots of z^n + p1 z^(n−1) + … + p_n are s times those of z^n + Σ (p_j / s^j) z^(n−j): with
  // s = max_j |p_j|^(1/j) the companion matrix's entries are at most 1 (Eigen's EigenSolver does not balance,
  // and an unbalanced companion matrix loses digits of its small eigenvalues).
  double s = 0;
  for (int j = 0; j < n; ++j) s = std::max(s, std::pow(std::abs(p[j]), 1.0 / (j + 1)));
  if (s == 0) return 0;
  // −p / s^j in the first row, ones on the subdiagonal.
  Eigen::MatrixXd companion = Eigen::MatrixXd::Zero(n, n);
  for (int j = 0; j < n; ++j) companion(0, j) = -p[j] / std::pow(s, j + 1);
  for (int i = 1; i < n; ++i) companion(i, i - 1) = 1;
  return s * companion.eigenvalues().cwiseAbs().maxCoeff();
}

}  // namespace ident::testing
