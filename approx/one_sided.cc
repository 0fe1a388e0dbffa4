#include "approx/one_sided.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "approx/weighting_polynomial.h"
#include "common/dense_decompositions.h"
#include "common/error.h"

namespace ident::approx {
namespace {

void Check(const NormalisedStatistics& s, const Eigen::VectorXd& h) {
  IDENT_REQUIRE(s.V.rows() >= 2 && s.V.rows() == s.V.cols(), "statistics V is {}x{}; need (rho+1)x(rho+1)", s.V.rows(),
                s.V.cols());
  IDENT_REQUIRE(h.size() == s.V.rows(), "data vector h has {} entries; V is {}x{}", h.size(), s.V.rows(), s.V.cols());
}

double LogDet(const Eigen::MatrixXd& A) {
  const Eigen::LDLT<Eigen::MatrixXd> ldlt = dense::Ldlt(A);
  return ldlt.vectorD().array().log().sum();
}

}  // namespace

DenseInnovation ComputeInnovation(const Eigen::MatrixXd& V, const Eigen::VectorXd& h) {
  const Eigen::Index rho = V.rows() - 1;
  const Eigen::VectorXd z = h.tail(rho);
  return {1 - h.dot(dense::Ldlt(V).solve(h)), 1 - z.dot(dense::Ldlt(V.bottomRightCorner(rho, rho)).solve(z))};
}

NormalisedStatistics RankOneCandidate(const NormalisedStatistics& s, const Eigen::VectorXd& h, double beta) {
  return {s.nu + 1, (1 - beta) * s.V + beta * h * h.transpose()};
}

OneSidedStepResult GaussianClass::Evaluate(const NormalisedStatistics& s, const Eigen::VectorXd& h, double beta) const {
  Check(s, h);
  OneSidedStepResult r{RankOneCandidate(s, h, beta), beta, 0, 0};
  const double nu = r.stats.nu, rho = static_cast<double>(h.size() - 1);
  // m·l(t−1)/s(t) = exp(−ω(νβ−1)θ̃'(Ṽ − hh')θ̃/2): bounded below by 1 only as described above [spec §7c].
  const double xi = ComputeInnovation(s.V, h).xi;
  const bool exact = std::abs(nu * beta - 1) <= 1e-15;
  r.log_gamma = (exact || (nu * beta < 1 && xi >= 0)) ? 0 : -std::numeric_limits<double>::infinity();
  const double log_det_v = LogDet(r.stats.V),
               log_det_vz = LogDet(r.stats.V.bottomRightCorner(h.size() - 1, h.size() - 1));
  const double Dy = std::exp(log_det_v - log_det_vz), a = (nu - delta - rho) / 2 + 1;
  r.log_integral = std::lgamma(a) - a * std::log(nu * Dy / 2) + rho / 2 * std::log(2 * M_PI / nu) - 0.5 * log_det_vz;
  return r;
}

OneSidedStepResult GaussianClass::Step(const NormalisedStatistics& s, const Eigen::VectorXd& h) const {
  return Evaluate(s, h, 1 / (s.nu + 1));  // eq. (55): β = 1/ν(t)
}

OneSidedStepResult StudentClass::Evaluate(const NormalisedStatistics& s, const Eigen::VectorXd& h, double beta) const {
  Check(s, h);
  OneSidedStepResult r{RankOneCandidate(s, h, beta), beta, 0, 0};
  const double nu = r.stats.nu, rho = static_cast<double>(h.size() - 1), kappa = (k + 1) / 2;
  const DenseInnovation in = ComputeInnovation(s.V, h);
  const WeightingProblem p{nu, in.xi, in.xi_z, static_cast<int>(rho), k, delta};
  const double r0 = std::min(0.0, in.xi);
  r.log_gamma =
      beta >= Beta0(p)  // essinf [spec §3]
          ? kappa * (nu * std::log(nu) + (1 - nu) * std::log(nu - 1) + std::log(beta) + (nu - 1) * std::log1p(-beta))
          : kappa * (nu * std::log1p(-beta * r0) - std::log1p(-r0));
  const double log_c = rho / 2 * std::log(M_PI) + std::lgamma(kappa * nu - rho / 2) - std::lgamma(kappa * nu) +
                       std::lgamma((nu - delta - rho + 2) / 2) + std::lgamma((k * nu + delta - 2) / 2) -
                       std::lgamma((nu - delta - rho + 2) / 2 + (k * nu + delta - 2) / 2);
  r.log_integral = log_c - (nu - delta - rho + 2) / 2 * LogDet(r.stats.V) +
                   (nu - delta - rho + 1) / 2 * LogDet(r.stats.V.bottomRightCorner(h.size() - 1, h.size() - 1));
  return r;
}

OneSidedStepResult StudentClass::Step(const NormalisedStatistics& s, const Eigen::VectorXd& h) const {
  Check(s, h);
  const DenseInnovation in = ComputeInnovation(s.V, h);
  const WeightingProblem p{s.nu + 1, in.xi, in.xi_z, static_cast<int>(h.size() - 1), k, delta};
  IDENT_REQUIRE(p.nu > NuHard(p.rho, k, delta), "nu(t) = {} <= nu_hard = {}: no valid one-sided step exists", p.nu,
                NuHard(p.rho, k, delta));
  return Evaluate(s, h, SolveWeight(p).beta);
}

static_assert(OneSidedApproximant<GaussianClass>);
static_assert(OneSidedApproximant<StudentClass>);

}  // namespace ident::approx
