#include "models/pseudo_linear_regressor.h"

#include <algorithm>
#include <cmath>

#include "common/error.h"

namespace ident::models {

PseudoLinearRegressor::PseudoLinearRegressor(const PolynomialStructure& structure,
                                             const OutputCleaningOptions& cleaning, Recursion recursion)
    : structure_(structure),
      arx_(structure.arx(), [&] {
        OutputCleaningOptions c = cleaning;
        if (c.warm_up == 0) c.warm_up = 10 * structure.num_parameters();
        return c;
      }()),
      theta_(Eigen::VectorXd::Zero(structure.num_parameters())),
      phi_(Eigen::VectorXd::Zero(structure.num_parameters())),
      past_e_(Eigen::VectorXd::Zero(structure.nc())),
      past_v_(Eigen::VectorXd::Zero(structure.nd())),
      past_w_(Eigen::VectorXd::Zero(structure.nf())),
      work_(Eigen::VectorXd::Zero(std::max(structure.nc(), structure.nf()))),
      recursion_(recursion),
      psi_(Eigen::VectorXd::Zero(structure.num_parameters())) {
  if (recursion_ == Recursion::kPredictionError) {
    IDENT_REQUIRE(structure.nf() == 0 || structure.nc() + structure.nd() == 0,
                  "{}: the recursive prediction-error method is for ARMAX and OE models", structure.ToString());
    past_psi_.setZero(structure.num_parameters(), structure.nf() > 0 ? structure.nf() : structure.nc());
  }
}

void PseudoLinearRegressor::Reset() {
  arx_.Reset();
  past_e_.setZero();
  past_v_.setZero();
  past_w_.setZero();
  past_psi_.setZero();
  newest_psi_ = 0;
  formed_ = gradient_ = false;
  samples_ = 0;
}

bool PseudoLinearRegressor::Next(const Eigen::Ref<const Eigen::VectorXd>& u, Eigen::Ref<Eigen::VectorXd> z) {
  const int rho = structure_.num_parameters();
  IDENT_REQUIRE(z.size() == rho, "regressor has {} entries; the model has {} parameters", z.size(), rho);
  const int n_arx = structure_.arx().num_parameters();
  const bool arx_formed = arx_.Next(u, phi_.head(n_arx));
  const long t = samples_++;
  formed_ = arx_formed && t >= structure_.first_regression_index();
  if (!formed_) return false;
  for (int k = 0; k < structure_.nc(); ++k) phi_(structure_.c_offset() + k) = past_e_(k);
  for (int k = 0; k < structure_.nd(); ++k) phi_(structure_.d_offset() + k) = -past_v_(k);
  for (int k = 0; k < structure_.nf(); ++k) phi_(structure_.f_offset() + k) = -past_w_(k);
  gradient_ = recursion_ == Recursion::kPredictionError && known_ && !fixed_;
  if (!gradient_) {
    z = phi_;
    return true;
  }
  // ψ(t) = φ(t) − Σ_k g_k ψ(t−k), G = C (ARMAX) or F (OE) of the tracked estimate.
  const int offset = structure_.nf() > 0 ? structure_.f_offset() : structure_.c_offset();
  psi_ = phi_;
  const Eigen::Index n = past_psi_.cols();
  for (Eigen::Index k = 0; k < n; ++k)
    psi_.noalias() -= theta_(offset + k) * past_psi_.col((newest_psi_ + k) % n);
  z = psi_;
  return true;
}

double PseudoLinearRegressor::LinearisedOutput(double y) const {
  return gradient_ ? y + theta_.dot(psi_ - phi_) : y;
}

void PseudoLinearRegressor::SetEstimate(const Eigen::Ref<const Eigen::VectorXd>& theta) {
  IDENT_REQUIRE(theta.size() == theta_.size(), "the estimate has {} entries; {} has {} parameters", theta.size(),
                structure_.ToString(), theta_.size());
  theta_ = theta;
  known_ = fixed_ = true;
  measured_w_ = false;
}

bool PseudoLinearRegressor::TrackEstimate(const Eigen::Ref<const Eigen::VectorXd>& theta, bool measured_noise_free) {
  if (fixed_) return false;
  // The first estimates after ClearEstimate rest on a few samples: w = y for kWarmUp·ρ of them.
  measured_w_ = measured_noise_free || tracked_ < static_cast<long>(kWarmUp) * theta_.size();
  ++tracked_;
  IDENT_REQUIRE(theta.size() == theta_.size(), "the estimate has {} entries; {} has {} parameters", theta.size(),
                structure_.ToString(), theta_.size());
  const bool stable =
      theta.allFinite() &&
      MonicStable(theta.data() + structure_.c_offset(), structure_.nc(), work_.data()) &&
      MonicStable(theta.data() + structure_.f_offset(), structure_.nf(), work_.data());
  if (!stable && known_) {
    ++projections_;
    return false;
  }
  theta_ = theta;
  known_ = true;
  return true;
}

void PseudoLinearRegressor::Shift(Eigen::VectorXd& history, double value) {
  const Eigen::Index m = history.size();
  for (Eigen::Index k = m - 1; k > 0; --k) history(k) = history(k - 1);
  if (m > 0) history(0) = value;
}

void PseudoLinearRegressor::Store(double y) {
  double e = 0, v = 0, w = y;
  if (formed_ && !known_) e = v = y;  // no estimate: y stands in, at the data's scale
  if (formed_ && known_) {
    const int n_a = structure_.na(), n_b = structure_.arx().num_parameters() - n_a;
    const int f = structure_.f_offset(), nf = structure_.nf();
    const double y_hat = theta_.dot(phi_);
    w = theta_.segment(n_a, n_b).dot(phi_.segment(n_a, n_b)) + theta_.segment(f, nf).dot(phi_.segment(f, nf));
    e = y - y_hat;
    v = y - theta_.head(n_a).dot(phi_.head(n_a)) - w;
    if (measured_w_) w = y;
  }
  // A missing sample (NaN) would otherwise stay in the recursions for good: it restarts them instead.
  if (!std::isfinite(e)) e = 0;
  if (!std::isfinite(v)) v = 0;
  if (!std::isfinite(w)) w = std::isfinite(y) ? y : 0;
  Shift(past_e_, e);
  Shift(past_v_, v);
  Shift(past_w_, w);
  if (past_psi_.cols() > 0) {
    // ψ(t) enters the filter; φ(t) stands in for it while no estimate is tracked (G = 1), 0 before t0. The
    // columns are a ring: the newest takes the place of the oldest.
    newest_psi_ = (newest_psi_ + past_psi_.cols() - 1) % past_psi_.cols();
    auto newest = past_psi_.col(newest_psi_);
    if (!formed_)
      newest.setZero();
    else
      newest = gradient_ ? psi_ : phi_;
    if (!newest.allFinite()) newest.setZero();
  }
  formed_ = gradient_ = false;
}

void PseudoLinearRegressor::PushOutput(double y) {
  arx_.PushOutput(y);
  Store(y);
}

double PseudoLinearRegressor::PushCheckedOutput(double y, double y_hat, double scale, bool flagged, bool judged) {
  const double stored = arx_.PushCheckedOutput(y, y_hat, scale, flagged, judged);
  Store(stored);
  return stored;
}

}  // namespace ident::models
