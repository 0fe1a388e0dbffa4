// Strong log-concavity calculus (Henningsson & Åström 2006, Def. 2, Theorems 1 and 2).
//
//   f ∈ LC(P⁻¹)  ⇔  f(x) / exp(−½ x'P⁻¹x) is log-concave                              [1, Def. 2]
//   Theorem 1 (encapsulation), written for the covariance-form bound P (f ∈ LC(P⁻¹)):
//     affine map  x ↦ A x + b of a density:  P ↦ A P A'   (density f(A⁻¹(x − b)) ∈ LC((A P A')⁻¹))
//     convolution f * g:                     P ↦ F + G
//     product f · g with g ∈ LC(Q):          P ↦ (P⁻¹ + Q)⁻¹  (Q may be singular, even 0)
//   Theorem 2 (covariance bound): a probability density in LC(P⁻¹) has covariance ≤ P.
//
// LcBound keeps the covariance-form strength P of a density and applies these rules; the operations
// have the structure of a Kalman filter applied to the corresponding Gaussians [1, sec. IV-B].
// The product rule is computed as P − P Q^{1/2}(I + Q^{1/2}' P Q^{1/2})⁻¹ Q^{1/2}' P, which accepts
// singular Q (a measurement that is log-concave but not strongly: Q = 0 leaves P unchanged).
//
// Example:
//   ident::approx::LcBound bound(P0);
//   bound.Affine(A); bound.Convolve(P_N);                 // dynamics + process noise
//   bound.Multiply(Q_M);                                  // a measurement in LC(Q_M)
//   // any Bayesian observer's covariance is now ≤ bound.P()  (Theorem 2)
//
// [1] T. Henningsson, K. J. Åström, "Log-concave Observers", MTNS 2006.
#pragma once

#include <Eigen/Core>

#include "common/dense_decompositions.h"
#include "common/error.h"

namespace ident::approx {

class LcBound {
 public:
  explicit LcBound(Eigen::MatrixXd P) : P_(std::move(P)) {
    IDENT_REQUIRE(P_.rows() >= 1 && P_.rows() == P_.cols() && P_.allFinite(), "bound P must be square and finite");
    IDENT_REQUIRE(dense::SymmetricEigen(P_, Eigen::ComputeEigenvectors).eigenvalues().minCoeff() > 0,
                  "bound P must be positive definite");
  }
  const Eigen::MatrixXd& P() const { return P_; }
  int dim() const { return static_cast<int>(P_.rows()); }

  // Thm 1, affine: density of A x + b.
  void Affine(const Eigen::Ref<const Eigen::MatrixXd>& A) {
    IDENT_REQUIRE(A.rows() == dim() && A.cols() == dim(), "A is {}×{}; bound has dimension {}", A.rows(), A.cols(),
                  dim());
    P_ = (A * P_ * A.transpose()).eval();
    Symmetrize();
  }
  // Thm 1, convolution with a density in LC(G⁻¹).
  void Convolve(const Eigen::Ref<const Eigen::MatrixXd>& G) {
    IDENT_REQUIRE(G.rows() == dim() && G.cols() == dim(), "G is {}×{}; bound has dimension {}", G.rows(), G.cols(),
                  dim());
    P_ += G;
    Symmetrize();
  }
  // Thm 1, product with a function in LC(Q), Q ≥ 0 (possibly singular).
  void Multiply(const Eigen::Ref<const Eigen::MatrixXd>& Q) {
    IDENT_REQUIRE(Q.rows() == dim() && Q.cols() == dim(), "Q is {}×{}; bound has dimension {}", Q.rows(), Q.cols(),
                  dim());
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig = dense::SymmetricEigen(Q);
    IDENT_REQUIRE(eig.eigenvalues().minCoeff() >= -1e-12 * (1 + Q.cwiseAbs().maxCoeff()),
                  "Q must be positive semidefinite");
    const Eigen::MatrixXd S =
        eig.eigenvectors() * eig.eigenvalues().cwiseMax(0.0).cwiseSqrt().asDiagonal();  // Q = S S'
    const Eigen::MatrixXd PS = P_ * S;
    const Eigen::MatrixXd M = Eigen::MatrixXd::Identity(dim(), dim()) + S.transpose() * PS;
    P_ -= PS * dense::Llt(M).solve(PS.transpose());
    Symmetrize();
  }
  // Rank-one product: a function of c'x in LC(q) (Q = q c c').
  void MultiplyRankOne(const Eigen::Ref<const Eigen::VectorXd>& c, double q) {
    IDENT_REQUIRE(c.size() == dim() && q >= 0 && std::isfinite(q), "rank-one strength needs c of size {} and q >= 0",
                  dim());
    if (q == 0) return;
    const Eigen::VectorXd Pc = P_ * c;
    P_ -= Pc * Pc.transpose() * (q / (1 + q * c.dot(Pc)));
    Symmetrize();
  }

 private:
  void Symmetrize() { P_ = 0.5 * (P_ + P_.transpose()).eval(); }
  Eigen::MatrixXd P_;
};

// Analytic bound on the velocity variance right after an event of the MEMS accelerometer with the
// modified event measurement (events ∈ LC(Q_M), Q_M = diag(σ_M⁻², 0)), t = time since the last event:
//   V(x̂2) ≤ σ² t / 3 + 2 σ_M² t⁻²                                                    [1, sec. V-A]
inline double MemsAnalyticVelocityBound(double noise_intensity, double sigma_m2, double t) {
  IDENT_REQUIRE(t > 0 && noise_intensity >= 0 && sigma_m2 >= 0, "need t > 0, sigma^2 >= 0, sigma_M^2 >= 0");
  return noise_intensity * t / 3 + 2 * sigma_m2 / (t * t);
}

}  // namespace ident::approx
