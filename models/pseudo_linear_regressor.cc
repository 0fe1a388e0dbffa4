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
    const int nc = structure.nc(), nd = structure.nd(), nf = structure.nf();
    box_jenkins_ = nf > 0 && nc + nd > 0;
    taps_ = box_jenkins_ ? std::max(nc + nf, nd) : (nf > 0 ? nf : nc);
    history_.setZero(structure.num_parameters(), 2 * taps_);
    if (box_jenkins_) {
      pre_.setZero(structure.num_parameters());
      cf_.setZero(nc + nf);
    }
  }
}

void PseudoLinearRegressor::Reset() {
  arx_.Reset();
  past_e_.setZero();
  past_v_.setZero();
  past_w_.setZero();
  history_.setZero();
  newest_ = 0;
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
  gradient_ = recursion_ == Recursion::kPredictionError && known_ && !fixed_ && !measured_w_;
  if (!gradient_) {
    z = phi_;
    return true;
  }
  if (box_jenkins_) {
    BoxJenkinsGradient();
    z = psi_;
    return true;
  }
  // ψ(t) = φ(t) − Σ_k g_k ψ(t−k), G = C (ARMAX) or F (OE) of the tracked estimate.
  const double* const g = theta_.data() + (structure_.nf() > 0 ? structure_.f_offset() : structure_.c_offset());
  psi_ = phi_;
  for (int k = 0; k < taps_; ++k) SubtractTap(g[k], k, 0, rho, psi_.data());
  z = psi_;
  return true;
}

void PseudoLinearRegressor::BoxJenkinsGradient() {
  // ŷ = (D/C)(B/F) u + (1 − D/C) y, so −∂ε/∂θ is (D/(C F)) φ in the B and F coordinates and φ/C in the C
  // and D ones. The history holds p(t): p = φ/(C F) in B and F (where ψ = D(q) p) and p = ψ = φ/C in C and D.
  const int nb = structure_.arx().num_parameters(), nc = structure_.nc(), nd = structure_.nd(), nf = structure_.nf();
  const int c = structure_.c_offset(), d = structure_.d_offset(), f = structure_.f_offset();
  const double* const theta = theta_.data();
  for (int k = 1; k <= nc + nf; ++k) {  // C(q)F(q) = 1 + Σ_k cf_k q^−k
    double h = (k <= nc ? theta[c + k - 1] : 0.0) + (k <= nf ? theta[f + k - 1] : 0.0);
    for (int i = std::max(1, k - nf); i <= std::min(nc, k - 1); ++i) h += theta[c + i - 1] * theta[f + k - i - 1];
    cf_(k - 1) = h;
  }
  // θ = [b, c, d, f]: B and F are the entries [0, nb) and [f, ρ), C and D the entries [c, f) between them.
  const int rho = structure_.num_parameters();
  pre_ = phi_;
  for (int k = 0; k < nc + nf; ++k) {
    SubtractTap(cf_(k), k, 0, nb, pre_.data());
    SubtractTap(cf_(k), k, f, rho, pre_.data());
  }
  for (int k = 0; k < nc; ++k) SubtractTap(theta[c + k], k, c, f, pre_.data());
  psi_ = pre_;
  for (int k = 0; k < nd; ++k) {
    AddTap(theta[d + k], k, 0, nb, psi_.data());
    AddTap(theta[d + k], k, f, rho, psi_.data());
  }
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
  if (taps_ > 0) {
    // ψ(t) (Box–Jenkins: p(t)) enters the filter; φ(t) stands in for it while no estimate is tracked
    // (G = 1), 0 before t0. The newest column moves one back (history_).
    newest_ = (newest_ + taps_ - 1) % taps_;
    const Eigen::VectorXd& value = !gradient_ ? phi_ : (box_jenkins_ ? pre_ : psi_);
    if (formed_ && value.allFinite())
      history_.col(newest_) = value;
    else
      history_.col(newest_).setZero();
    history_.col(newest_ + taps_) = history_.col(newest_);
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
