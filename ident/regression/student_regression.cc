#include "ident/regression/student_regression.h"

#include <algorithm>

#include <fmt/core.h>

namespace ident {

RegressionPrior StudentRegressionOptions::DefaultPrior(int num_parameters) const {
  return RegressionPrior::Diagonal(num_parameters, num_parameters + dof + delta, 1.0, 1e-3);
}

std::string StudentRegressionOptions::Validate(int rho) const {
  if (rho < 1) return fmt::format("number of parameters = {}; need at least 1", rho);
  if (!(std::isfinite(dof) && dof > 0)) return fmt::format("dof = {}; need a finite k > 0", dof);
  if (delta != 0 && delta != 1) return fmt::format("delta = {}; need 0 or 1", delta);
  if (std::string e = forgetting.Validate(); !e.empty()) return e;
  if (startup_window < 0 || startup_window == 1)
    return fmt::format("startup_window = {}; need 0 (automatic) or at least 2 samples", startup_window);
  if (prior && prior->num_parameters() != rho)
    return fmt::format("prior V0 is {}x{}; the model needs {}x{} (rho = {}, y first)", prior->V0.rows(),
                       prior->V0.cols(), rho + 1, rho + 1, rho);
  const double nu0 = prior ? prior->nu0 : rho + dof + delta;
  return ForgettingAdmissibility(rho, nu0, forgetting, dof, delta);
}

std::string ForgettingAdmissibility(int rho, double nu0, const ForgettingOptions& forgetting, double dof, int delta) {
  const double nu_hard = approx::NuHard(rho, dof, delta);
  // The smallest ν(t), t ≥ 1, of the forgetting recursion [spec §7b]: ν(t) moves monotonically from
  // ν(1) towards its fixed point 1/(1−λ) (exponential) or ν_a + 1/(1−λ) (stabilised, ν_a = ν(0)).
  const double lambda = forgetting.factor;
  const double nu1 = forgetting.stabilised ? nu0 + 1 : lambda * nu0 + 1;
  double nu_inf = std::numeric_limits<double>::infinity();
  if (lambda < 1) nu_inf = forgetting.stabilised ? nu0 + 1 / (1 - lambda) : 1 / (1 - lambda);
  const double nu_min = std::min(nu1, nu_inf);
  if (!(nu_min > nu_hard)) {
    if (nu1 <= nu_hard && lambda < 1 && !forgetting.stabilised && nu0 + 1 > nu_hard)
      return fmt::format(
          "forgetting = {} is inadmissible with nu0 = {}: the first step has nu(1) = forgetting*nu0 + 1 = {} <= "
          "nu_hard = {} (max(rho+delta-1, (k+3-delta)/k, rho/(k+1)) for rho = {}, k = {}, delta = {}); raise the "
          "forgetting factor",
          lambda, nu0, nu1, nu_hard, rho, dof, delta);
    if (nu1 <= nu_hard)
      return fmt::format(
          "nu0 = {} is inadmissible: the first step has nu(1) = {} <= nu_hard = {} (max(rho+delta-1, "
          "(k+3-delta)/k, rho/(k+1)) for rho = {}, k = {}, delta = {}); no valid one-sided step exists",
          nu0, nu1, nu_hard, rho, dof, delta);
    return fmt::format(
        "forgetting = {} is inadmissible: nu(t) tends to {} <= nu_hard = {} (rho = {}, k = {}, delta = {}); "
        "need 1/(1-forgetting) > nu_hard",
        lambda, nu_inf, nu_hard, rho, dof, delta);
  }
  return {};
}

}  // namespace ident
