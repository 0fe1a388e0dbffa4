#include "models/pseudo_linear_regressor.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "common/error.h"

namespace ident::models {

PseudoLinearRegressor::PseudoLinearRegressor(const PolynomialStructure& structure,
                                             const OutputCleaningOptions& cleaning, Recursion recursion)
    : structure_(structure),
      arx_(structure.arx(),
           [&] {
             OutputCleaningOptions c = cleaning;
             if (c.warm_up == 0) c.warm_up = 10 * structure.num_parameters();
             return c;
           }()),
      theta_(Eigen::VectorXd::Zero(structure.num_parameters())),
      phi_(Eigen::VectorXd::Zero(structure.num_parameters())),
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
  phi_.tail(structure_.num_parameters() - structure_.c_offset()).setZero();
  history_.setZero();
  newest_ = 0;
  formed_ = gradient_ = false;
  samples_ = 0;
}

[[gnu::always_inline]] inline void PseudoLinearRegressor::FilterRange(const double* g, int ng, const double* h, int nh,
                                                                      int begin, int end, const double* in,
                                                                      double* __restrict pre,
                                                                      double* __restrict psi) const {
  const Eigen::Index stride = history_.rows();
  const double* __restrict const newest = history_.data() + newest_ * stride;
  int i = begin;
  for (; i + 1 < end; i += 2) {
    double a0 = in[i], a1 = in[i + 1];
    const double* p = newest + i;
    for (int k = 0; k < ng; ++k, p += stride) {
      a0 -= g[k] * p[0];
      a1 -= g[k] * p[1];
    }
    pre[i] = a0;
    pre[i + 1] = a1;
    if (!psi) continue;
    p = newest + i;
    for (int k = 0; k < nh; ++k, p += stride) {
      a0 += h[k] * p[0];
      a1 += h[k] * p[1];
    }
    psi[i] = a0;
    psi[i + 1] = a1;
  }
  if (i < end) {
    double a = in[i];
    const double* p = newest + i;
    for (int k = 0; k < ng; ++k, p += stride) a -= g[k] * p[0];
    pre[i] = a;
    if (!psi) return;
    p = newest + i;
    for (int k = 0; k < nh; ++k, p += stride) a += h[k] * p[0];
    psi[i] = a;
  }
}

bool PseudoLinearRegressor::Next(const Eigen::Ref<const Eigen::VectorXd>& u, Eigen::Ref<Eigen::VectorXd> z) {
  const int rho = structure_.num_parameters();
  IDENT_REQUIRE(z.size() == rho, "regressor has {} entries; the model has {} parameters", z.size(), rho);
  const int n_arx = structure_.arx().num_parameters();
  const bool arx_formed = arx_.Next(u, phi_.head(n_arx));
  const long t = samples_++;
  formed_ = arx_formed && t >= structure_.first_regression_index();
  if (!formed_) return false;
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
  FilterRange(g, taps_, nullptr, 0, 0, rho, phi_.data(), psi_.data(), nullptr);
  z = psi_;
  return true;
}

void PseudoLinearRegressor::BoxJenkinsGradient() {
  // ŷ = (D/C)(B/F) u + (1 − D/C) y, so −∂ε/∂θ is (D/(C F)) φ in the B and F coordinates and φ/C in the C
  // and D ones. The history holds p(t): p = φ/(C F) in B and F (where ψ = D(q) p) and p = ψ = φ/C in C and D.
  const int nb = structure_.arx().num_parameters(), nc = structure_.nc(), nd = structure_.nd(), nf = structure_.nf();
  const int c = structure_.c_offset(), d = structure_.d_offset(), f = structure_.f_offset();
  const double* const theta = theta_.data();
  // C(q)F(q) = 1 + Σ_k cf_k q^−k with cf_k = c_k + f_k + Σ_i c_i f_{k−i}, the products added in the order
  // i = 1, 2, … (row i of the product adds c_i·f).
  double* const cf = cf_.data();
  for (int k = 1; k <= nc + nf; ++k)
    cf[k - 1] = (k <= nc ? theta[c + k - 1] : 0.0) + (k <= nf ? theta[f + k - 1] : 0.0);
  for (int i = 1; i <= nc; ++i) {
    const double ci = theta[c + i - 1];
    const double* const fj = theta + f;
    double* const out = cf + i;
    for (int j = 0; j < nf; ++j) out[j] += ci * fj[j];
  }
  // θ = [b, c, d, f]: B and F are the entries [0, nb) and [f, ρ), C and D the entries [c, f) between them.
  const int rho = structure_.num_parameters();
  double* const pre = pre_.data();
  double* const psi = psi_.data();
  FilterRange(cf, nc + nf, theta + d, nd, 0, nb, phi_.data(), pre, psi);
  FilterRange(cf, nc + nf, theta + d, nd, f, rho, phi_.data(), pre, psi);
  FilterRange(theta + c, nc, nullptr, 0, c, f, phi_.data(), pre, psi);  // ψ = p in C and D
}

double PseudoLinearRegressor::LinearisedOutput(double y) const { return gradient_ ? y + theta_.dot(psi_ - phi_) : y; }

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
  const bool stable = theta.allFinite() &&
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

void PseudoLinearRegressor::Shift(double* history, int n, double value) {
  // A carried swap rather than a backward copy, which the compiler turns into a call to memmove.
  double carry = value;
  for (int k = 0; k < n; ++k) std::swap(carry, history[k]);
}

void PseudoLinearRegressor::Store(double y) {
  double e = 0, v = 0, w = y;
  if (formed_ && !known_) e = v = y;  // no estimate: y stands in, at the data's scale
  if (formed_ && known_) {
    // θ'φ by parts, θ = [a, b, c, d, f]: ŷ = A + W + N with A the a part, W = b + f parts, N = c + d parts.
    const int n_a = structure_.na(), c = structure_.c_offset(), f = structure_.f_offset();
    const int rho = structure_.num_parameters();
    const double* const th = theta_.data();
    const double* const ph = phi_.data();
    const auto part = [th, ph](int begin, int end) {
      double s = 0;
      for (int i = begin; i < end; ++i) s += th[i] * ph[i];
      return s;
    };
    const double a_part = part(0, n_a);
    w = part(n_a, c) + part(f, rho);
    e = y - ((a_part + w) + part(c, f));
    v = y - a_part - w;
    if (measured_w_) w = y;
  }
  // A missing sample (NaN) would otherwise stay in the recursions for good: it restarts them instead.
  if (!std::isfinite(e)) e = 0;
  if (!std::isfinite(v)) v = 0;
  if (!std::isfinite(w)) w = std::isfinite(y) ? y : 0;
  Shift(phi_.data() + structure_.c_offset(), structure_.nc(), e);
  Shift(phi_.data() + structure_.d_offset(), structure_.nd(), -v);
  Shift(phi_.data() + structure_.f_offset(), structure_.nf(), -w);
  if (taps_ > 0) {
    // ψ(t) (Box–Jenkins: p(t)) enters the filter; φ(t) stands in for it while no estimate is tracked
    // (G = 1), 0 before t0. The newest column moves one back (history_).
    newest_ = newest_ > 0 ? newest_ - 1 : taps_ - 1;
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
