// What the batch robust regressions share (internal to ident/regression/; see ident/regression/batch_regression.h):
// checks of the regression data, the column-pivoted QR that orthonormalises the regressors, weighted
// least squares in that basis, the median absolute value, uniform indices for elemental subsets.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <random>

#include <Eigen/Core>

#include "common/dense_decompositions.h"
#include "common/error.h"

namespace ident::batch_regression_detail {

inline constexpr double kInf = std::numeric_limits<double>::infinity();
inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Throws InvalidArgument naming the first problem with the regression data.
inline void RequireRegressionData(const Eigen::Ref<const Eigen::MatrixXd>& Z,
                                  const Eigen::Ref<const Eigen::VectorXd>& y) {
  IDENT_REQUIRE(Z.cols() >= 1, "Z has no columns; need at least one regressor");
  IDENT_REQUIRE(Z.rows() == y.size(), "Z has {} rows but y has {} entries; need one row per sample", Z.rows(),
                y.size());
  IDENT_REQUIRE(Z.rows() > Z.cols(), "n = {} samples for rho = {} regressors; need n > rho", Z.rows(), Z.cols());
  IDENT_REQUIRE(Z.allFinite(), "Z has a non-finite entry");
  IDENT_REQUIRE(y.allFinite(), "y has a non-finite entry");
}

// Z P = Q R (column-pivoted Householder QR), with the thin Q and T = P R⁻¹, so that β = T⁻¹Θ are the
// coefficients on the orthonormal columns of Q: ZΘ = Qβ, Θ = Tβ, Cov(Θ) = T Cov(β) T'.
struct Orthonormalised {
  Eigen::MatrixXd Q;
  Eigen::MatrixXd T;
  Eigen::Index rank = 0;
};

inline Orthonormalised Orthonormalise(const Eigen::Ref<const Eigen::MatrixXd>& Z) {
  const Eigen::Index p = Z.cols();
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr = dense::ColPivQr(Z);
  Orthonormalised f;
  f.rank = qr.rank();
  if (f.rank < p) return f;
  f.Q = dense::LeadingQColumns(qr, p);
  const Eigen::MatrixXd Rinv = dense::UpperTriangularInverse(qr.matrixR().topLeftCorner(p, p));
  f.T = qr.colsPermutation() * Rinv;
  return f;
}

inline Orthonormalised RequireFullRank(const Eigen::Ref<const Eigen::MatrixXd>& Z) {
  Orthonormalised f = Orthonormalise(Z);
  IDENT_REQUIRE(f.rank == Z.cols(), "Z has column rank {} < rho = {}; need full column rank", f.rank, Z.cols());
  return f;
}

// argmin_β Σ w_i (y_i − β'q_i)² by the normal equations on the orthonormal Q (well conditioned unless the
// weights are); nullopt-like: returns false if Q'WQ is not positive definite.
// `Qw`: workspace for W·Q (resized to Q's shape if it is not).
inline bool WeightedFit(const Eigen::MatrixXd& Q, const Eigen::Ref<const Eigen::VectorXd>& y, const Eigen::VectorXd& w,
                        Eigen::VectorXd& beta, Eigen::MatrixXd& Qw) {
  Qw = Q.array().colwise() * w.array();
  const Eigen::LLT<Eigen::MatrixXd> llt = dense::Llt(Qw.transpose() * Q);
  if (llt.info() != Eigen::Success) return false;
  beta = llt.solve(Qw.transpose() * y);
  return beta.allFinite();
}
inline bool WeightedFit(const Eigen::MatrixXd& Q, const Eigen::Ref<const Eigen::VectorXd>& y, const Eigen::VectorXd& w,
                        Eigen::VectorXd& beta) {
  Eigen::MatrixXd Qw;
  return WeightedFit(Q, y, w, beta, Qw);
}

// Median of |v| (the mean of the two middle values for even n, as R's median). `a`: workspace.
inline double MedianAbs(const Eigen::VectorXd& v, std::vector<double>& a) {
  a.assign(v.data(), v.data() + v.size());
  for (double& x : a) x = std::abs(x);
  const std::size_t mid = a.size() / 2;
  std::nth_element(a.begin(), a.begin() + static_cast<std::ptrdiff_t>(mid), a.end());
  const double upper = a[mid];
  if (a.size() % 2 == 1) return upper;
  return 0.5 * (upper + *std::max_element(a.begin(), a.begin() + static_cast<std::ptrdiff_t>(mid)));
}
inline double MedianAbs(const Eigen::VectorXd& v) {
  std::vector<double> a;
  return MedianAbs(v, a);
}

// A uniform index in [0, bound) from the generator's raw output (rejection sampling): unlike the std
// distributions, the same sequence on every standard library.
inline std::size_t UniformIndex(std::mt19937_64& rng, std::size_t bound) {
  const std::uint64_t b = bound;
  const std::uint64_t limit = std::numeric_limits<std::uint64_t>::max() / b * b;
  std::uint64_t x = rng();
  while (x >= limit) x = rng();
  return static_cast<std::size_t>(x % b);
}

// ---- Cauchy maximum likelihood on (β, η = log γ) -------------------------------------------------------

}  // namespace ident::batch_regression_detail
