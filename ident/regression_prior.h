// The prior (ν(0), V(0)) of the regression estimators, in the normalised extended-information form.
//
//   V(0) = [[V_y, V_zy'], [V_zy, V_z]]  ((ρ+1)x(ρ+1), y first),  ν(0) > 0 pseudo-samples.
//   Prior guess Θ̂(0) = V_z^{-1} V_zy;  prior noise scale² D_y(0) = V_y − V_zy'Θ̂(0)            [spec §2, §8]
//
// Example:
//   auto prior = ident::RegressionPrior::Diagonal(/*rho=*/4, /*nu0=*/6, /*vy0=*/1, /*vz0=*/1e-3);
#pragma once

#include <Eigen/Core>

namespace ident {

struct RegressionPrior {
  double nu0 = 1.0;
  Eigen::MatrixXd V0;  // (ρ+1)x(ρ+1) symmetric positive definite, y first

  int num_parameters() const { return static_cast<int>(V0.rows()) - 1; }

  // ν(0) = nu0, V(0) = diag(vy0, vz0·I_ρ)  (the command line's --nu0/--vy0/--vz0).
  static RegressionPrior Diagonal(int rho, double nu0, double vy0, double vz0);

  // From a prior mean Θ0, covariance P0 of Θ, noise scale σ0 and weight ν0 > ρ+δ [spec §8]:
  //   V_z(0) = σ0² P0^{-1}/(ν0−δ−ρ),  V_zy(0) = V_z(0)Θ0,  V_y(0) = σ0² + Θ0'V_z(0)Θ0.
  static RegressionPrior FromGuess(const Eigen::VectorXd& theta0, const Eigen::MatrixXd& P0, double sigma0,
                                   double nu0, int delta);

  // Flat prior for least squares: information ν0·V0 = 1e-12·I (negligible against any real
  // record's Z'Z, so RLS reproduces batch least squares).
  static RegressionPrior Flat(int rho);

  // Throws InvalidArgument naming the field if ν0 is not positive and finite, or V0 is not
  // square, symmetric and positive definite.
  void Validate() const;
};

}  // namespace ident
