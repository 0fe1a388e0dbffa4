// Gauss rules for a normal density on a half-line, the kink of the generalised Gaussian at 0 taken out.
//
// On t ≥ 0, with t = s²:  ∫_0^∞ e^{−(t − α)²/2} g(t) dt = ∫_0^∞ W_α(s) g(s²) ds,  W_α(s) = 2s·e^{−(s² − α)²/2},
// and HalfLineRules<N> holds the N-point Gauss rule of each weight W_α, α = −12, −11.75, …, 12:
// Σ w_i g(t_i) is exact when g(s²) is a polynomial in s of degree < 2N. g(t) = e^{−c·t^p} becomes e^{−c·s^{2p}},
// smooth in s for p = 1, 1.5, 2 and for other p singular at s = 0 only at order 2p ≥ 2, which is what makes
// these rules converge where a rule in t meets |t|^p's singularity at order p. A weight between grid
// points is written as its nearest grid weight times e^{δt − (α² − α_j²)/2}, δ = α − α_j, a smooth factor.
//
// The rules come from the discretised Stieltjes procedure (Gautschi, "Orthogonal Polynomials: Computation
// and Approximation", 2004, sec. 2.2.3) on a composite 20-point Gauss–Legendre discretisation of W_α, and
// Golub–Welsch on the Jacobi matrix; built once per process.
#pragma once

#include <Eigen/Core>

namespace ident::models::internal {

inline constexpr double kHalfLineAlphaMax = 12;
inline constexpr double kHalfLineAlphaStep = 0.25;
inline constexpr int kHalfLineRuleCount = 97;  // 2·12/0.25 + 1
// The largest prior variance v (in f's units) for which LogConcaveNoise uses these rules; beyond it e^{−(√v·t)^p}
// varies too fast across the weight.
inline constexpr double kHalfLineMaxVariance = 0.5625;

template <int N>
struct HalfLineRule {
  double alpha = 0;
  Eigen::Array<double, N, 1> s, t, log_t, w;  // nodes s_i, t_i = s_i², log t_i; weights w_i
};

template <int N>
class HalfLineRules {
 public:
  static const HalfLineRules& Get();  // thread-safe; built at the first call

  // The rule whose α_j is nearest α, |α| ≤ kHalfLineAlphaMax.
  const HalfLineRule<N>& Nearest(double alpha) const noexcept;

 private:
  HalfLineRules();
  HalfLineRule<N> rules_[kHalfLineRuleCount];
};

extern template class HalfLineRules<10>;  // the sizes LogConcaveNoise uses
extern template class HalfLineRules<12>;
extern template class HalfLineRules<16>;
extern template class HalfLineRules<20>;
extern template class HalfLineRules<28>;
extern template class HalfLineRules<40>;

}  // namespace ident::models::internal
