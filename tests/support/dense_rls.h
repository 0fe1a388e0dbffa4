// Plain covariance-form RLS with exponential forgetting: the test and benchmark oracle for the
// LD-factorised RecursiveLeastSquares. Textbook recursion (Ljung, System Identification, eq. 11.63):
//
//   ê = y − θ'z,  K = P z/(λ + z'P z),  θ ← θ + K ê,  P ← (P − K z'P)/λ,
//   residual sum S ← λS + λê²/(λ + z'P z),  ν ← λν + 1,
//
// with P = (νV_z)⁻¹ the inverse unnormalised information, so that θ, ν and D_y = S/ν equal the
// normalised LD recursion's exactly in exact arithmetic. Deliberately plain (no factorisation);
// the only safeguard is re-symmetrising P after each step, without which rounding makes P
// asymmetric and the recursion diverges within ~10^4 steps at λ = 0.99. An independent
// reference, not a production estimator.
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include "common/dense_decompositions.h"
#include "common/error.h"
#include "ident/regression/regression_prior.h"

namespace ident {

template <int Rho = Eigen::Dynamic>
class BasicDenseRls {
 public:
  using Vector = Eigen::Matrix<double, Rho, 1>;
  using Matrix = Eigen::Matrix<double, Rho, Rho>;

  BasicDenseRls(const RegressionPrior& prior, double lambda) : lambda_(lambda) {
    prior.Validate();
    const Eigen::Index rho = prior.num_parameters();
    const Eigen::MatrixXd Vz = prior.V0.bottomRightCorner(rho, rho);
    const Eigen::VectorXd Vzy = prior.V0.bottomLeftCorner(rho, 1);
    const Eigen::LLT<Eigen::MatrixXd> llt = dense::Llt(Vz);
    theta_ = llt.solve(Vzy);
    P_ = llt.solve(Eigen::MatrixXd::Identity(rho, rho)) / prior.nu0;
    nu_ = prior.nu0;
    S_ = prior.nu0 * (prior.V0(0, 0) - Vzy.dot(theta_));
    Pz_.resize(rho);
    K_.resize(rho);
  }

  template <class Derived>
  void Update(double y, const Eigen::MatrixBase<Derived>& z) {
    const double e = y - theta_.dot(z);
    Pz_.noalias() = P_ * z;
    const double denom = lambda_ + z.dot(Pz_);
    K_ = Pz_ / denom;
    theta_ += K_ * e;
    P_.noalias() -= K_ * Pz_.transpose();
    P_ = (0.5 / lambda_) * (P_ + P_.transpose()).eval();  // keep P symmetric (else it drifts and blows up)
    S_ = lambda_ * S_ + lambda_ * e * e / denom;
    nu_ = lambda_ * nu_ + 1;
  }

  const Vector& parameters() const { return theta_; }
  const Matrix& P() const { return P_; }
  double nu() const { return nu_; }
  double Dy() const { return S_ / nu_; }

 private:
  double lambda_;
  Vector theta_, Pz_, K_;
  Matrix P_;
  double nu_ = 0, S_ = 0;
};

using DenseRls = BasicDenseRls<Eigen::Dynamic>;

}  // namespace ident
