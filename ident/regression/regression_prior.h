// The prior (ν(0), V(0)) of the regression estimators, in the normalised extended-information form.
//
//   V(0) = [[V_y, V_zy'], [V_zy, V_z]]  ((ρ+1)x(ρ+1), y first),  ν(0) > 0 pseudo-samples.
//   Prior guess Θ̂(0) = V_z^{-1} V_zy;  prior noise scale² D_y(0) = V_y − V_zy'Θ̂(0)            [spec §2, §8]
//
// Example:
//   auto prior = ident::RegressionPrior::Diagonal(/*rho=*/4, /*nu0=*/6, /*vy0=*/1, /*vz0=*/1e-3);
//   auto robust = ident::RegressionPrior::FromWindow(window, /*nu0=*/6, /*delta=*/1);  // rows (y, z')
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
  static RegressionPrior FromGuess(const Eigen::VectorXd& theta0, const Eigen::MatrixXd& P0, double sigma0, double nu0,
                                   int delta);

  // The data-driven prior from a window of samples (row t = (y(t), z(t)')), spec §8 recipe with
  //   Θ0 = theta0 (empty: 0),  σ0 = noise_scale (0: s_y),  P0 = (10·s_y)²·M⁻¹,  M = Z'Z/n,
  // i.e. V_z(0) = σ0²·M/(100·s_y²·(ν0−δ−ρ)): the prior spread of Θ'z for a typical regressor is ten times
  // the output's robust scale s_y = RobustScale(y). M, the regressors' second moments about 0, makes the
  // prior equivariant: under y → c·y + b'z, z → T·z (T regular, e.g. an intercept with an uncentred
  // regressor) and Θ0 → T⁻ᵀ(c·Θ0 + b), V(0) transforms as spec §10.8 asks. A regressor that is zero
  // throughout the window gets M_ii = 1; a singular M is regularised by 1e−9·diag(M).
  static RegressionPrior FromWindow(const Eigen::Ref<const Eigen::MatrixXd>& window, double nu0, int delta,
                                    double noise_scale = 0, const Eigen::VectorXd& theta0 = {});

  // Flat prior for least squares: information ν0·V0 = 1e-12·I (negligible against any real
  // record's Z'Z, so RLS reproduces batch least squares).
  static RegressionPrior Flat(int rho);
  // The same flat prior in the data's own scale: ν0 = 1e-12, V0 = diag(m), where m = (mean y², mean z_1², …,
  // mean z_ρ²) over the samples to be fitted — information 1e-12 of one average sample in every coordinate,
  // so the prior's pull on θ̂ is ~1e-12/N relative whatever the units (RLS reproduces least squares on
  // data of scale 1e-5 as on data of scale 1). Scaling y or a regressor scales the prior along (spec §10.8).
  // Throws InvalidArgument unless every m_i is in [1e-280, 1e280] (beyond that, give a prior or rescale).
  static RegressionPrior Flat(const Eigen::VectorXd& mean_squares);

  // Throws InvalidArgument naming the field if ν0 is not positive and finite, or V0 is not
  // square, symmetric and positive definite.
  void Validate() const;
};

// Robust scale of a sample: 1.4826·MAD (median absolute deviation from the median; = σ for Gaussian
// data, ignores up to half the sample being outliers); the RMS if the MAD is 0; 1 if that is 0 too
// (or the sample is empty).
double RobustScale(const Eigen::Ref<const Eigen::VectorXd>& x);
// 1.4826·MAD alone: 0 when more than half of the sample is one value (or the sample is empty).
double MadScale(const Eigen::Ref<const Eigen::VectorXd>& x);

}  // namespace ident
