// The quadrature moments of LogConcaveNoise (models/noise_density.h): Gauss–Hermite rules in the prior, the
// Gauss–Legendre rule around the mode of the tilted density, and the reference by adaptive quadrature.
#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

#include <Eigen/Core>
#include <Eigen/Eigenvalues>
#include <boost/math/quadrature/gauss.hpp>

#include "common/dense_decompositions.h"
#include "models/internal/noise_density_shared.h"
#include "models/measurement.h"
#include "models/noise_density.h"

namespace ident::models {

using internal::GengaussPower;
using internal::Rho;

namespace {

// Probabilists' Gauss–Hermite rules, E g(X) ≈ Σ w_i g(x_i) for X ~ N(0, 1), exact for polynomials of degree
// < 2n: nodes from the Jacobi matrix (Golub–Welsch) polished by Newton on the orthonormal recurrence
// p_(k+1) = (x p_k − √k p_(k−1))/√(k+1), weights the Christoffel numbers 1/Σ_(k<n) p_k(x_i)². Built once.
struct HermiteRule {
  int n = 0;
  std::array<double, 64> x{}, w{};
};
constexpr std::array<int, 9> kHermiteSizes = {8, 12, 16, 20, 24, 32, 40, 48, 64};

const std::array<HermiteRule, 9>& HermiteRules() {
  static const std::array<HermiteRule, 9> rules = [] {
    std::array<HermiteRule, 9> out{};
    for (std::size_t r = 0; r < kHermiteSizes.size(); ++r) {
      const int n = kHermiteSizes[r];
      Eigen::VectorXd diag = Eigen::VectorXd::Zero(n), sub(n - 1);
      for (int k = 1; k < n; ++k) sub(k - 1) = std::sqrt(static_cast<double>(k));
      const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig =
          dense::SymmetricTridiagonalEigen(diag, sub, Eigen::EigenvaluesOnly);
      out[r].n = n;
      for (int i = 0; i < n; ++i) {
        double x = eig.eigenvalues()(i), norm = 0;
        for (int it = 0; it < 3; ++it) {
          double p0 = 1, p1 = x;
          norm = 1 + x * x;
          for (int k = 1; k + 1 < n; ++k) {
            const double p2 = (x * p1 - std::sqrt(static_cast<double>(k)) * p0) / std::sqrt(k + 1.0);
            p0 = p1;
            p1 = p2;
            norm += p1 * p1;
          }
          const double pn = (x * p1 - std::sqrt(n - 1.0) * p0) / std::sqrt(static_cast<double>(n));
          x -= pn / (std::sqrt(static_cast<double>(n)) * p1);  // p_n' = √n p_(n−1)
        }
        out[r].x[i] = x;
        out[r].w[i] = 1 / norm;
      }
      double total = 0;
      for (int i = 0; i < n; ++i) total += out[r].w[i];
      for (int i = 0; i < n; ++i) out[r].w[i] /= total;  // Σ w = 1 to rounding
    }
    return out;
  }();
  return rules;
}

// g(y, s) = f(y − s) as a projected measurement on a scalar state (the quadrature reference).
class ResidualMeasurement final : public ProjectedMeasurement {
 public:
  explicit ResidualMeasurement(const LogConcaveNoise& noise)
      : ProjectedMeasurement(Eigen::VectorXd::Ones(1)), noise_(noise) {}
  std::string name() const override { return noise_.ToString(); }
  double LogLikelihoodScalar(double y, double s) const override { return noise_.LogDensity(y - s); }
  double ScalarStrength(double) const override { return 0.0; }
  bool IsValidOutput(double y) const override { return std::isfinite(y); }

 protected:
  Pieces SupportPieces(double y) const override {
    Pieces p;
    using F = LogConcaveNoise::Family;
    if (noise_.family() == F::kLaplace || noise_.family() == F::kGeneralizedGaussian) p.kinks[0] = y;
    if (noise_.family() == F::kHuber) {
      p.kinks[0] = y - noise_.shape();
      p.kinks[1] = y + noise_.shape();
    }
    return p;
  }

 private:
  const LogConcaveNoise& noise_;
};

// The 10-point Gauss–Legendre rule on [−1, 1], every node (both signs) in one array.
using Legendre10 = Eigen::Array<double, 10, 1>;
struct LegendreRule {
  Legendre10 x, w;
};

const LegendreRule& Legendre() {
  static const LegendreRule rule = [] {
    using Gauss = boost::math::quadrature::gauss<double, 10>;
    LegendreRule out;
    int n = 0;
    for (std::size_t i = 0; i < Gauss::abscissa().size(); ++i)
      for (int side : {1, -1}) {
        if (side < 0 && Gauss::abscissa()[i] == 0) continue;
        out.x(n) = side * Gauss::abscissa()[i];
        out.w(n++) = Gauss::weights()[i];
      }
    return out;
  }();
  return rule;
}

// |r|^p at every node (r ≥ 0), as GengaussPower; r = 0 gives exp(−∞) = 0.
template <class Nodes>
Nodes GengaussPowerAtNodes(const Nodes& ar, double p) {
  if (p == 1.5) return ar * ar.sqrt();
  if (p == 2) return ar.square();
  if (p == 1) return ar;
  return (p * ar.log()).exp();
}

// ρ(r) at every node of a rule, as Rho() (noise_density_shared.h) for logistic and gengauss, in Eigen's
// vectorised log/exp/sqrt: the integrand is the moments' whole cost.
template <class Nodes>
Nodes RhoAtNodes(LogConcaveNoise::Family family, double p, const Nodes& r) {
  const Nodes ar = r.abs();
  if (family == LogConcaveNoise::Family::kLogistic) return ar + 2 * (-ar).exp().log1p();
  return GengaussPowerAtNodes(ar, p);
}

}  // namespace

void internal::BuildHermiteRules() {
  HermiteRules();
  Legendre();
}

TiltedMoments LogConcaveNoise::HermiteMoments(double a, double v, int rule_index) const noexcept {
  // Z = E f(a + √v X) = e^{−ρ(a) − log_norm}·E e^{ρ(a) − ρ(r)}: the factor e^{−ρ(a)} taken out so that
  // outliers do not underflow; logistic's e^{ρ(a) − ρ(r)} = e^{|a| − |r|}·(1 + e^{−|a|})²/(1 + e^{−|r|})².
  // The nodes in Eigen arrays of at most 64 entries (on the stack), for its vectorised exp.
  using Nodes = Eigen::Array<double, Eigen::Dynamic, 1, Eigen::ColMajor, 64, 1>;
  const HermiteRule& rule = HermiteRules()[static_cast<std::size_t>(rule_index)];
  const Eigen::Map<const Eigen::ArrayXd> x(rule.x.data(), rule.n), w(rule.w.data(), rule.n);
  const double sd = std::sqrt(v), aa = std::abs(a);
  const bool logistic = family_ == Family::kLogistic;
  const double rho_a = logistic ? 0.0 : GengaussPower(aa, shape_);
  const Nodes d = sd * x;
  const Nodes ar = (a + d).abs();
  Nodes wv;
  if (logistic) {
    const Nodes e_rel = (aa - ar).exp();  // e^{|a| − |r|}; e^{−|r|} = e_rel·e^{−|a|}
    wv = w * e_rel / (1 + std::exp(-aa) * e_rel).square();
  } else {
    wv = w * (rho_a - GengaussPowerAtNodes(ar, shape_)).exp();
  }
  const double z = wv.sum(), m1 = (wv * d).sum(), m2 = (wv * d.square()).sum();
  if (!(z > 0) || !std::isfinite(z)) return {};
  const double mean_d = m1 / z;
  const double log_z = std::log(z) + (logistic ? -aa : -rho_a - log_norm_);
  return {log_z, a + mean_d, std::max(0.0, m2 / z - mean_d * mean_d), true};
}

TiltedMoments LogConcaveNoise::RuleMoments(double a, double v) const noexcept {
  // log h(r) = −ρ(r) − (r − a)²/(2v); h' = 0 at the mode, in [min(0, a), max(0, a)] since ψ(0) = 0 and ψ
  // has the sign of r. Safeguarded Newton on the decreasing −ψ(r) − (r − a)/v.
  const bool logistic = family_ == Family::kLogistic;
  // ρ'' (logistic: (1 − tanh²(r/2))/2 ≤ 1/4; gengauss: p(p − 1)|r|^(p−2), evaluated at |r| ≥ 1/2 so
  // that the kink of |r|^p at 0 does not shrink the width to nothing).
  auto curvature = [&](double r) {
    if (logistic) {
      const double t = std::tanh(0.5 * r);
      return 0.5 * (1 - t * t);
    }
    const double ar = std::max(std::abs(r), 0.5);
    return shape_ * (shape_ - 1) * (shape_ == 1.5 ? 1 / std::sqrt(ar) : shape_ == 2 ? 1.0 : std::pow(ar, shape_ - 2));
  };
  double lo = std::min(0.0, a), hi = std::max(0.0, a), r = std::clamp(a / (1 + 0.25 * v), lo, hi);
  // The mode only places the panels (which reach 16 widths either side) and scales the integrand, so a
  // millionth of the width is close enough.
  for (int i = 0; i < 200; ++i) {
    const double g = -Score(r) - (r - a) / v;  // decreasing in r
    if (g > 0)
      lo = r;
    else
      hi = r;
    const double hessian = curvature(r) + 1 / v;
    double next = r + g / hessian;
    if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
    const bool done = std::abs(next - r) <= 1e-6 / std::sqrt(hessian) || hi - lo <= 1e-15 * (1 + std::abs(r));
    r = next;
    if (done) break;
  }
  const double width = 1 / std::sqrt(curvature(r) + 1 / v);
  const double log_peak = -Rho(family_, shape_, r) - 0.5 * (r - a) * (r - a) / v;
  if (!logistic && std::abs(r) >= 12 * width) return ModeHermiteMoments(a, v, r, width, log_peak);
  // log h is concave: ±16 widths, widened until log h has fallen by 45 from its peak at both ends (so the
  // mass beyond is below e^{−45} of the peak's per unit slope), in panels of width at most 2 (f's own
  // scale; 12 at least, 400 at most) of 10 Gauss–Legendre points.
  // gengauss: a panel boundary at r = 0, where |r|^p is not smooth.
  auto log_h = [&](double u) { return -Rho(family_, shape_, u) - 0.5 * (u - a) * (u - a) / v; };
  double half = 16 * width;
  for (int i = 0; i < 40 && std::max(log_h(r - half), log_h(r + half)) > log_peak - 45; ++i) half *= 1.5;
  constexpr int kMaxPanels = 400;
  const int panels = std::clamp(static_cast<int>(std::ceil(half)), 12, kMaxPanels);
  const double panel = 2 * half / panels;
  std::array<double, kMaxPanels + 12> cuts{};
  int n = 0;
  for (int p = 0; p <= panels; ++p) cuts[n++] = r - half + p * panel;
  if (!logistic && cuts[0] < 0 && cuts[panels] > 0) {
    // |r|^p at 0: a boundary there and panels graded geometrically towards it (exponential convergence
    // for the r^p singularity instead of GL's algebraic one).
    cuts[n++] = 0;
    for (double g = 0.25; g > 1e-3; g *= 0.25)
      for (double c : {-g * panel, g * panel})
        if (c > cuts[0] && c < cuts[panels]) cuts[n++] = c;
    std::sort(cuts.begin(), cuts.begin() + n);
  }
  const LegendreRule& gl = Legendre();
  const double half_precision = 0.5 / v;
  Legendre10 z_sum = Legendre10::Zero(), m1_sum = Legendre10::Zero(), m2_sum = Legendre10::Zero();
  for (int p = 0; p + 1 < n; ++p) {
    const double centre = 0.5 * (cuts[p] + cuts[p + 1]), scale = 0.5 * (cuts[p + 1] - cuts[p]);
    const Legendre10 rr = centre + scale * gl.x, d = rr - r;
    const Legendre10 h =
        scale * gl.w * (-RhoAtNodes(family_, shape_, rr) - half_precision * (rr - a).square() - log_peak).exp();
    z_sum += h;
    m1_sum += h * d;
    m2_sum += h * d.square();
  }
  const double z = z_sum.sum(), m1 = m1_sum.sum(), m2 = m2_sum.sum();
  if (!(z > 0) || !std::isfinite(z)) return {};
  const double mean_d = m1 / z;
  const double var = std::max(0.0, m2 / z - mean_d * mean_d);
  // Z = ∫ f(r)·N(r; a, v) dr = e^{log_peak − log_norm}·z/√(2πv).
  return {log_peak - log_norm_ + std::log(z) - 0.5 * std::log(2 * std::numbers::pi * v), r + mean_d, var, true};
}

TiltedMoments LogConcaveNoise::ModeHermiteMoments(double a, double v, double mode, double width,
                                                  double log_peak) const noexcept {
  // r = mode + width·x: ∫ h(r) dr = width·√(2π)·E[h(mode + width·X)·e^{X²/2}], X ~ N(0, 1), by the 20-point
  // rule. log h(mode + width·x) − log_peak + x²/2 is the departure of log h from its osculating parabola
  // (curvature 1/width² at the mode): smooth and slowly varying while the kink of |r|^p at 0 is 12 widths away.
  constexpr int kRule = 3;  // 20 points (kHermiteSizes)
  const HermiteRule& rule = HermiteRules()[kRule];
  // The differences from the mode are formed without cancellation (log h is of the order of a², its change
  // over a width of order 1): ρ(A) − ρ(B) = (A − B)·(…) with A − B exact, and the Gaussian's
  // ((r − a)² − (mode − a)²)/(2v) = wx·(2(mode − a) + wx)/(2v). |r| and |mode| share a sign since the rule's
  // nodes lie within 8 widths.
  const double am = std::abs(mode), sign = mode >= 0 ? 1.0 : -1.0, p = shape_;
  const double sqrt_am = std::sqrt(am), am_p = GengaussPower(am, p);
  double z = 0, m1 = 0, m2 = 0;
  for (int i = 0; i < rule.n; ++i) {
    const double x = rule.x[i], wx = width * x, d = sign * wx, ar = am + d;
    double d_rho;
    if (p == 1)  // p = 2 has a closed form (ResidualMoments)
      d_rho = d;
    else if (p == 1.5)
      d_rho = d * (ar * ar + ar * am + am * am) / (ar * std::sqrt(ar) + am * sqrt_am);
    else
      d_rho = am_p * std::expm1(p * std::log1p(d / am));
    const double value = std::exp(-d_rho - wx * (2 * (mode - a) + wx) / (2 * v) + 0.5 * x * x);
    const double wv = rule.w[i] * value;
    z += wv;
    m1 += wv * x;
    m2 += wv * x * x;
  }
  if (!(z > 0) || !std::isfinite(z)) return {};
  const double mean_x = m1 / z;
  const double var = width * width * std::max(0.0, m2 / z - mean_x * mean_x);
  // Z = e^{log_peak − log_norm}·width·√(2π)·z / √(2πv).
  return {log_peak - log_norm_ + std::log(z * width) - 0.5 * std::log(v), mode + width * mean_x, var, true};
}

TiltedMoments LogConcaveNoise::QuadratureResidualMoments(double a, double v) const {
  // r = y − s with y = 0: r ~ N(a, v) ⇔ s ~ N(−a, v); the moments of r are those of −s.
  const ResidualMeasurement measurement(*this);
  const TiltedMoments t = measurement.QuadratureTilt(0.0, -a, v);
  if (!t.ok) return t;
  return {t.log_normalizer, -t.mean, t.variance, true};
}

}  // namespace ident::models
