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
    past_psi_.setZero(structure.num_parameters(), box_jenkins_ ? std::max(nc + nf, nd) : (nf > 0 ? nf : nc));
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
  const int offset = structure_.nf() > 0 ? structure_.f_offset() : structure_.c_offset();
  psi_ = phi_;
  const Eigen::Index n = past_psi_.cols();
  for (Eigen::Index k = 0, column = newest_psi_; k < n; ++k) {  // ψ(t−1−k): the ring from the newest on
    psi_.noalias() -= theta_(offset + k) * past_psi_.col(column);
    if (++column == n) column = 0;
  }
  z = psi_;
  return true;
}

void PseudoLinearRegressor::Grouped(const Eigen::VectorXd& x, Eigen::VectorXd& out) const {
  // θ's order [b, c, d, f] to the ring's [b, f, c, d]: the coordinates filtered alike are contiguous.
  const int nb = structure_.arx().num_parameters(), nc = structure_.nc(), nd = structure_.nd(), nf = structure_.nf();
  out.head(nb) = x.head(nb);
  out.segment(nb, nf) = x.segment(structure_.f_offset(), nf);
  out.segment(nb + nf, nc + nd) = x.segment(structure_.c_offset(), nc + nd);
}

void PseudoLinearRegressor::BoxJenkinsGradient() {
  // ŷ = (D/C)(B/F) u + (1 − D/C) y, so −∂ε/∂θ is (D/(C F)) φ in the B and F coordinates and φ/C in the C
  // and D ones. The ring holds p(t) grouped as [b, f, c, d]: p = φ/(C F) in B, F (where ψ = D(q) p) and
  // p = ψ = φ/C in C, D.
  const int nc = structure_.nc(), nd = structure_.nd(), nf = structure_.nf();
  const int nbf = structure_.arx().num_parameters() + nf, ncd = nc + nd;
  const int c = structure_.c_offset(), d = structure_.d_offset(), f = structure_.f_offset();
  for (int k = 1; k <= nc + nf; ++k) {  // C(q)F(q) = 1 + Σ_k cf_k q^−k
    double h = (k <= nc ? theta_(c + k - 1) : 0.0) + (k <= nf ? theta_(f + k - 1) : 0.0);
    for (int i = std::max(1, k - nf); i <= std::min(nc, k - 1); ++i) h += theta_(c + i - 1) * theta_(f + k - i - 1);
    cf_(k - 1) = h;
  }
  // Plain loops on the ring's columns: at these lengths (a few entries per tap) the per-expression set-up
  // of Eigen's dynamic-size segment operations costs more than their arithmetic. Each entry takes its
  // taps in the order k = 1, 2, … as a vector operation per tap would.
  // p(t−k) for k = 1, 2, …: the ring's columns from the newest on, stepped without a division.
  const Eigen::Index n = past_psi_.cols(), rows = past_psi_.rows();
  const double* const ring = past_psi_.data();
  const auto each_past = [&](int taps, auto&& op) {
    Eigen::Index column = newest_psi_;
    for (int k = 1; k <= taps; ++k) {
      op(k, ring + column * rows);
      if (++column == n) column = 0;
    }
  };
  Grouped(phi_, pre_);
  double* const pre = pre_.data();
  each_past(nc + nf, [&](int k, const double* p) {
    const double g = cf_(k - 1);
    for (int i = 0; i < nbf; ++i) pre[i] -= g * p[i];
  });
  each_past(nc, [&](int k, const double* p) {
    const double g = theta_(c + k - 1);
    for (int i = 0; i < ncd; ++i) pre[nbf + i] -= g * p[nbf + i];
  });
  // ψ = D(q) p in B and F, back in θ's order [b, c, d, f]; ψ = p in C and D.
  const int nb = nbf - nf;
  double* const psi = psi_.data();
  for (int i = 0; i < nbf; ++i) psi[i < nb ? i : f + i - nb] = pre[i];
  each_past(nd, [&](int k, const double* p) {
    const double g = theta_(d + k - 1);
    for (int i = 0; i < nbf; ++i) psi[i < nb ? i : f + i - nb] += g * p[i];
  });
  for (int i = 0; i < ncd; ++i) psi[c + i] = pre[nbf + i];
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
    if (!formed_) {
      newest.setZero();
    } else if (!box_jenkins_) {
      newest = gradient_ ? psi_ : phi_;
    } else {  // p(t), grouped (BoxJenkinsGradient)
      if (!gradient_) Grouped(phi_, pre_);
      newest = pre_;
    }
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
