#include "ident/control/pole_placement.h"

#include <cmath>

#include <fmt/core.h>

#include "common/error.h"

namespace ident::control {

Eigen::VectorXd Multiply(const Eigen::VectorXd& p, const Eigen::VectorXd& q) {
  IDENT_REQUIRE(p.size() >= 1 && q.size() >= 1, "polynomial product needs non-empty polynomials");
  Eigen::VectorXd r = Eigen::VectorXd::Zero(p.size() + q.size() - 1);
  for (Eigen::Index i = 0; i < p.size(); ++i)
    for (Eigen::Index j = 0; j < q.size(); ++j) r(i + j) += p(i) * q(j);
  return r;
}

std::string PolePlacementOptions::Validate(int na, int nb, int nk) const {
  if (na < 0) return fmt::format("na = {}; need na >= 0", na);
  if (nb < 1) return fmt::format("nb = {}; need nb >= 1", nb);
  if (nk < 1) return fmt::format("nk = {}; need a delay nk >= 1", nk);
  if (am.size() < 1 || !am.allFinite() || am(0) != 1.0) return "am must be finite with am(0) = 1";
  if (ao.size() < 1 || !ao.allFinite() || ao(0) != 1.0) return "ao must be finite with ao(0) = 1";
  const int deg_a = na + (integral_action ? 1 : 0);
  const int deg_b = nk + nb - 1;
  const int deg_ac = static_cast<int>(am.size() + ao.size()) - 2;
  if (deg_ac > deg_a + deg_b - 1)
    return fmt::format("deg(am*ao) = {}; the minimum-degree design allows at most deg A' + deg B - 1 = {}", deg_ac,
                       deg_a + deg_b - 1);
  return {};
}

PolePlacement::PolePlacement(int na, int nb, int nk, const PolePlacementOptions& options)
    : na_(na), nb_(nb), options_(options) {
  const std::string error = options.Validate(na, nb, nk);
  IDENT_REQUIRE(error.empty(), "{}", error);
  deg_a_ = na + (options.integral_action ? 1 : 0);
  deg_b_ = nk + nb - 1;
  n_ = deg_a_ + deg_b_;
  ac_ = Eigen::VectorXd::Zero(n_);
  const Eigen::VectorXd ac = Multiply(options.am, options.ao);
  ac_.head(ac.size()) = ac;
  a_full_ = Eigen::VectorXd::Zero(deg_a_ + 1);
  b_full_ = Eigen::VectorXd::Zero(deg_b_ + 1);
  x_ = Eigen::VectorXd::Zero(n_);
  M_ = Eigen::MatrixXd::Zero(n_, n_);
  lu_ = Eigen::PartialPivLU<Eigen::MatrixXd>(n_);
  R_ = Eigen::VectorXd::Zero(deg_b_ + (options.integral_action ? 1 : 0));
  R_(0) = 1;
  S_ = Eigen::VectorXd::Zero(deg_a_);
  T_ = Eigen::VectorXd::Zero(options.ao.size());
}

DesignStatus PolePlacement::Design(const Eigen::Ref<const Eigen::VectorXd>& a,
                                   const Eigen::Ref<const Eigen::VectorXd>& b) noexcept {
  if (a.size() != na_ || b.size() != nb_ || !a.allFinite() || !b.allFinite()) return DesignStatus::kInvalidModel;
  // A' = A or A(1 − q⁻¹).
  a_full_.setZero();
  a_full_(0) = 1;
  a_full_.segment(1, na_) = a;
  if (options_.integral_action)
    for (int i = deg_a_; i >= 1; --i) a_full_(i) -= a_full_(i - 1);
  b_full_.setZero();
  b_full_.tail(nb_) = b;  // B = q^{−nk}(b1 + …): coefficients nk … nk+nb−1
  const double b_at_1 = b.sum();
  if (!(std::abs(b_at_1) > 1e-12 * (b.cwiseAbs().sum() + 1e-300))) return DesignStatus::kNotControllable;
  // Sylvester matrix: columns j < deg B: q^{−j} A';  columns deg B + j (j < deg A'): q^{−j} B.
  M_.setZero();
  for (int j = 0; j < deg_b_; ++j) M_.col(j).segment(j, deg_a_ + 1) = a_full_;
  for (int j = 0; j < deg_a_; ++j) M_.col(deg_b_ + j).segment(j, deg_b_ + 1) = b_full_;
  lu_.compute(M_);
  const auto diag = lu_.matrixLU().diagonal().cwiseAbs();
  if (!(diag.minCoeff() > 1e-10 * diag.maxCoeff())) return DesignStatus::kNotControllable;
  x_.noalias() = lu_.solve(ac_);
  if (!x_.allFinite()) return DesignStatus::kNotControllable;
  x_(0) = 1;  // the q⁰ equation reads R̄(0)·A'(0) = Ac(0), i.e. R̄(0) = 1 exactly (B(0) = 0)
  // R = R̄ or (1 − q⁻¹)R̄.
  const auto rbar = x_.head(deg_b_);
  R_.setZero();
  R_.head(deg_b_) = rbar;
  if (options_.integral_action)
    for (int i = deg_b_; i >= 1; --i) R_(i) -= R_(i - 1);
  S_ = x_.tail(deg_a_);
  // T = t0 Ao, t0 = Am(1)/B(1).
  T_ = (options_.am.sum() / b_at_1) * options_.ao;
  return DesignStatus::kOk;
}

}  // namespace ident::control
