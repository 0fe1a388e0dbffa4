#include "ident/regression/regression_prior.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include <Eigen/Core>

#include "common/dense_decompositions.h"
#include "common/error.h"
#include "ident/linalg/ld_factor.h"

namespace ident {

RegressionPrior RegressionPrior::Diagonal(int rho, double nu0, double vy0, double vz0) {
  IDENT_REQUIRE(rho >= 1, "number of parameters = {}; need at least 1", rho);
  IDENT_REQUIRE(std::isfinite(vy0) && vy0 > 0, "vy0 = {}; need a positive prior output variance", vy0);
  IDENT_REQUIRE(std::isfinite(vz0) && vz0 > 0, "vz0 = {}; need a positive prior regressor variance", vz0);
  RegressionPrior prior;
  prior.nu0 = nu0;
  prior.V0 = Eigen::MatrixXd::Identity(rho + 1, rho + 1) * vz0;
  prior.V0(0, 0) = vy0;
  prior.Validate();
  return prior;
}

RegressionPrior RegressionPrior::FromGuess(const Eigen::VectorXd& theta0, const Eigen::MatrixXd& P0, double sigma0,
                                           double nu0, int delta) {
  const int rho = static_cast<int>(theta0.size());
  IDENT_REQUIRE(rho >= 1 && P0.rows() == rho && P0.cols() == rho, "prior covariance P0 is {}x{}; need {}x{}", P0.rows(),
                P0.cols(), rho, rho);
  IDENT_REQUIRE(std::isfinite(sigma0) && sigma0 > 0, "sigma0 = {}; need a positive noise scale", sigma0);
  IDENT_REQUIRE(nu0 > rho + delta, "nu0 = {}; need nu0 > rho + delta = {}", nu0, rho + delta);
  const Eigen::LLT<Eigen::MatrixXd> llt = dense::Llt(P0);
  IDENT_REQUIRE(llt.info() == Eigen::Success, "prior covariance P0 is not positive definite");
  const Eigen::MatrixXd Vz = sigma0 * sigma0 * dense::Inverse(llt) / (nu0 - delta - rho);
  RegressionPrior prior;
  prior.nu0 = nu0;
  prior.V0.resize(rho + 1, rho + 1);
  prior.V0.bottomRightCorner(rho, rho) = 0.5 * (Vz + Vz.transpose());
  prior.V0.bottomLeftCorner(rho, 1) = Vz * theta0;
  prior.V0.topRightCorner(1, rho) = prior.V0.bottomLeftCorner(rho, 1).transpose();
  prior.V0(0, 0) = sigma0 * sigma0 + theta0.dot(Vz * theta0);
  prior.Validate();
  return prior;
}

RegressionPrior RegressionPrior::FromWindow(const Eigen::Ref<const Eigen::MatrixXd>& window, double nu0, int delta,
                                            double noise_scale, const Eigen::VectorXd& theta0) {
  const int rho = static_cast<int>(window.cols()) - 1;
  IDENT_REQUIRE(rho >= 1, "prior window has {} columns; need (y, z1..z_rho), rho >= 1", window.cols());
  IDENT_REQUIRE(window.rows() >= 2, "prior window has {} rows; need at least 2 samples", window.rows());
  IDENT_REQUIRE(window.allFinite(), "prior window has a non-finite entry");
  IDENT_REQUIRE(nu0 > rho + delta, "nu0 = {}; need nu0 > rho + delta = {}", nu0, rho + delta);
  IDENT_REQUIRE(std::isfinite(noise_scale) && noise_scale >= 0, "noise_scale = {}; need >= 0 (0: s_y)", noise_scale);
  IDENT_REQUIRE(theta0.size() == 0 || (theta0.size() == rho && theta0.allFinite()),
                "prior centre has {} entries; need {} finite values", theta0.size(), rho);
  const double sy = RobustScale(window.col(0));
  const double sigma0 = noise_scale > 0 ? noise_scale : sy;
  const auto Z = window.rightCols(rho);
  Eigen::MatrixXd M = Z.transpose() * Z / static_cast<double>(window.rows());
  for (int i = 0; i < rho; ++i)
    if (!(M(i, i) > 0)) M(i, i) = 1;
  M.diagonal() *= 1 + 1e-9;
  // V_z(0) = σ0² P0⁻¹/(ν0−δ−ρ), P0 = (10·s_y)²·M⁻¹ [spec §8]; then V_zy(0) = V_z(0)Θ0, V_y(0) = σ0² + Θ0'V_z(0)Θ0.
  const Eigen::MatrixXd Vz = sigma0 * sigma0 / (100 * sy * sy * (nu0 - delta - rho)) * M;
  const Eigen::VectorXd t0 = theta0.size() ? theta0 : Eigen::VectorXd::Zero(rho);
  RegressionPrior prior;
  prior.nu0 = nu0;
  prior.V0.resize(rho + 1, rho + 1);
  prior.V0.bottomRightCorner(rho, rho) = Vz;
  prior.V0.bottomLeftCorner(rho, 1) = Vz * t0;
  prior.V0.topRightCorner(1, rho) = prior.V0.bottomLeftCorner(rho, 1).transpose();
  prior.V0(0, 0) = sigma0 * sigma0 + t0.dot(Vz * t0);
  prior.Validate();
  return prior;
}

double MadScale(const Eigen::Ref<const Eigen::VectorXd>& x) {
  const std::size_t n = static_cast<std::size_t>(x.size());
  if (n == 0) return 0.0;
  std::vector<double> v(x.data(), x.data() + n);
  auto median = [&] {
    std::nth_element(v.begin(), v.begin() + n / 2, v.end());
    return v[n / 2];
  };
  const double med = median();
  for (std::size_t i = 0; i < n; ++i) v[i] = std::abs(x(i) - med);
  return 1.4826 * median();
}

double RobustScale(const Eigen::Ref<const Eigen::VectorXd>& x) {
  double s = MadScale(x);
  if (!(s > 0) && x.size() > 0) s = std::sqrt(x.squaredNorm() / static_cast<double>(x.size()));
  return s > 0 && std::isfinite(s) ? s : 1.0;
}

RegressionPrior RegressionPrior::Flat(int rho) {
  IDENT_REQUIRE(rho >= 1, "number of parameters = {}; need at least 1", rho);
  RegressionPrior prior;
  prior.nu0 = 1e-12;
  prior.V0 = Eigen::MatrixXd::Identity(rho + 1, rho + 1);
  return prior;
}

RegressionPrior RegressionPrior::Flat(const Eigen::VectorXd& mean_squares) {
  IDENT_REQUIRE(mean_squares.size() >= 2, "{} mean squares; need y's and at least one regressor's",
                mean_squares.size());
  for (Eigen::Index i = 0; i < mean_squares.size(); ++i)
    IDENT_REQUIRE(mean_squares(i) >= 1e-280 && mean_squares(i) <= 1e280,
                  "mean square {} of coordinate {} is outside [1e-280, 1e280]; rescale the data or give a prior",
                  mean_squares(i), i);
  RegressionPrior prior;
  prior.nu0 = 1e-12;
  prior.V0 = mean_squares.asDiagonal();
  return prior;
}

void RegressionPrior::Validate() const {
  IDENT_REQUIRE(std::isfinite(nu0) && nu0 > 0, "nu0 = {}; need a positive number of prior degrees", nu0);
  IDENT_REQUIRE(V0.rows() >= 2 && V0.rows() == V0.cols(), "prior matrix V0 is {}x{}; need (rho+1)x(rho+1), rho >= 1",
                V0.rows(), V0.cols());
  try {
    LdFactor<> check(V0);  // throws if V0 is not symmetric positive definite
  } catch (const InvalidArgument& e) {
    throw InvalidArgument(fmt::format("prior {}", e.what()));  // "prior matrix V ..."
  }
}

}  // namespace ident
