// The Gauss rules of models/internal/half_line_rules.h.
#include "models/internal/half_line_rules.h"
#include "common/dense_decompositions.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include <Eigen/Eigenvalues>
#include <boost/math/quadrature/gauss.hpp>

namespace ident::models::internal {

namespace {

// W_α on [0, s_max] in 64 panels of 20 Gauss–Legendre points: s_max = √(max(α, 0) + 12) + 1/2 puts the end
// where (s² − α)²/2 ≥ 72, W_α's mass beyond below e^{−70} of its peak; each panel is narrower than W_α's
// width 1/(2√α) for α ≤ 12.
struct Discretised {
  std::vector<double> s, w;
};

Discretised DiscretiseWeight(double alpha) {
  using Gauss = boost::math::quadrature::gauss<double, 20>;
  constexpr int kPanels = 64;
  const double s_max = std::sqrt(std::max(alpha, 0.0) + 12) + 0.5, width = s_max / kPanels;
  Discretised out;
  out.s.reserve(kPanels * 20);
  out.w.reserve(kPanels * 20);
  for (int p = 0; p < kPanels; ++p) {
    const double centre = (p + 0.5) * width;
    for (std::size_t i = 0; i < Gauss::abscissa().size(); ++i)
      for (int side : {1, -1}) {
        const double s = centre + side * 0.5 * width * Gauss::abscissa()[i];
        const double d = s * s - alpha;
        out.s.push_back(s);
        out.w.push_back(0.5 * width * Gauss::weights()[i] * 2 * s * std::exp(-0.5 * d * d));
      }
  }
  return out;
}

template <int N>
HalfLineRule<N> BuildRule(double alpha) {
  const Discretised d = DiscretiseWeight(alpha);
  const Eigen::Map<const Eigen::ArrayXd> s(d.s.data(), static_cast<Eigen::Index>(d.s.size()));
  const Eigen::Map<const Eigen::ArrayXd> w(d.w.data(), static_cast<Eigen::Index>(d.w.size()));
  // Stieltjes: orthonormal p_(k+1) = ((s − a_k) p_k − b_k p_(k−1)) / b_(k+1) in the discrete inner product.
  const double mass = w.sum();
  Eigen::ArrayXd p_prev = Eigen::ArrayXd::Zero(s.size()), p = Eigen::ArrayXd::Constant(s.size(), 1 / std::sqrt(mass));
  Eigen::VectorXd diag(N), sub(N - 1);
  for (int k = 0; k < N; ++k) {
    diag(k) = (w * s * p.square()).sum();
    if (k + 1 == N) break;
    Eigen::ArrayXd q = (s - diag(k)) * p;
    if (k > 0) q -= sub(k - 1) * p_prev;
    sub(k) = std::sqrt((w * q.square()).sum());
    p_prev = p;
    p = q / sub(k);
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig =
      dense::SymmetricTridiagonalEigen(diag, sub, Eigen::ComputeEigenvectors);
  HalfLineRule<N> rule;
  rule.alpha = alpha;
  for (int i = 0; i < N; ++i) {
    rule.s(i) = eig.eigenvalues()(i);
    rule.w(i) = mass * eig.eigenvectors()(0, i) * eig.eigenvectors()(0, i);
  }
  rule.t = rule.s.square();
  rule.log_t = rule.t.log();
  return rule;
}

}  // namespace

template <int N>
HalfLineRules<N>::HalfLineRules() {
  for (int j = 0; j < kHalfLineRuleCount; ++j) rules_[j] = BuildRule<N>(-kHalfLineAlphaMax + j * kHalfLineAlphaStep);
}

template <int N>
const HalfLineRules<N>& HalfLineRules<N>::Get() {
  static const HalfLineRules rules;
  return rules;
}

template <int N>
const HalfLineRule<N>& HalfLineRules<N>::Nearest(double alpha) const noexcept {
  const auto j = std::lround((alpha + kHalfLineAlphaMax) / kHalfLineAlphaStep);
  return rules_[std::clamp<long>(j, 0, kHalfLineRuleCount - 1)];
}

template class HalfLineRules<10>;
template class HalfLineRules<12>;
template class HalfLineRules<16>;
template class HalfLineRules<20>;
template class HalfLineRules<28>;
template class HalfLineRules<40>;

}  // namespace ident::models::internal
