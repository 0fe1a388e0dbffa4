// Seeded random matrices for the MAP-smoother tests (map_smoother_test.cc, map_smoother_fast_path_test.cc).
#pragma once

#include <random>

#include <Eigen/Core>

namespace ident::duality_test {

// r x c with independent N(0, scale²) entries, drawn row by row.
inline Eigen::MatrixXd RandomMatrix(std::mt19937& rng, int r, int c, double scale = 1.0) {
  std::normal_distribution<double> N(0, scale);
  Eigen::MatrixXd A(r, c);
  for (int i = 0; i < r; ++i)
    for (int j = 0; j < c; ++j) A(i, j) = N(rng);
  return A;
}

// scale·(AA' + I/2) with A = RandomMatrix(rng, n, n): symmetric positive definite.
inline Eigen::MatrixXd RandomSpd(std::mt19937& rng, int n, double scale = 1.0) {
  const Eigen::MatrixXd A = RandomMatrix(rng, n, n);
  return scale * (A * A.transpose() + 0.5 * Eigen::MatrixXd::Identity(n, n));
}

}  // namespace ident::duality_test
