// The one-sided recursive approximation of Bayes' rule (Kárný & Hangos 1988) as a pluggable framework.
//
// Idea. The exact posterior after a data item, p ∝ m(d|w)·l(w|t−1), leaves the chosen class. The step
// picks the member l(t) of the class that lies below it everywhere, l(t) ≤ m·l(t−1) a.e., and has the
// largest integral (a one-sided, maximin Kullback–Leibler bound; paper Lemma 4 [spec §3]). Writing the
// member as l(t) = γ·s(t) with a shape s(t) from the class, the best γ for a shape is the essential
// infimum γ = essinf m·l(t−1)/s(t), so the step maximises over shapes
//
//     log H = log γ + log ∫ s(t) dμ_δ          (the two quantities the maximin criterion trades).
//
// Classes with normalised statistics (ν, V) — V the (ρ+1)×(ρ+1) extended information matrix, y first —
// keep the optimum in the rank-one family V(β) = (1−β)V + βhh', ν ← ν+1 (paper Lemmas 6–8), so a
// step is a 1-D search over the weight β. Forgetting (spec §7b) is applied to (ν, V) before the step.
//
// Requirements on an approximant class A (the concept OneSidedApproximant):
//   A::Evaluate(stats, h, β) -> OneSidedStepResult  the candidate V(β) with log γ(β) and log ∫ s(β)
//   A::Step(stats, h)        -> OneSidedStepResult  the maximin member (closed form where one exists)
// Classes here:
//   GaussianClass   normal–gamma, m ∝ ω^{1/2}exp(−ω(θ̃'h)²/2): exact, β = 1/ν (normalised RLS) [spec §7c]
//   StudentClass    ω^{ν/2}(1+ωθ̃'Vθ̃)^{−κν} for t_k noise; k = 1 is the paper's Cauchy class (39);
//                   β = root of the corrected weighting cubic (approx/weighting_polynomial.h) [spec §2–§5, §7a]
// These dense implementations are the framework's reference (O(ρ³) per step); the estimators in
// ident/ run the same steps on the LD factorisation in O(ρ²).
//
// Example:
//   ident::approx::StudentClass cauchy{.k = 1, .delta = 1};
//   ident::approx::NormalisedStatistics s{6, V0};
//   s = cauchy.Step(s, h).stats;
#pragma once

#include <concepts>

#include <Eigen/Core>

namespace ident::approx {

struct NormalisedStatistics {
  double nu = 0;      // ν: sample count including the prior weight
  Eigen::MatrixXd V;  // normalised extended information matrix, SPD, y first
};

struct OneSidedStepResult {
  NormalisedStatistics stats;  // (ν+1, V(β))
  double beta = 0;             // the weight of the data item
  double log_gamma = 0;        // log essinf m·l(t−1)/s(t) (up to the model's constant factor)
  double log_integral = 0;     // log ∫ s(t) dμ_δ
  double objective() const { return log_gamma + log_integral; }
};

template <class A>
concept OneSidedApproximant = requires(const A& a, const NormalisedStatistics& s, const Eigen::VectorXd& h,
                                       double beta) {
  { a.Evaluate(s, h, beta) } -> std::same_as<OneSidedStepResult>;
  { a.Step(s, h) } -> std::same_as<OneSidedStepResult>;
};

// ξ = 1 − h'V⁻¹h and ξ_z = 1 − z'V_z⁻¹z by dense solves [spec §3].
struct DenseInnovation {
  double xi = 0, xi_z = 0;
};
DenseInnovation ComputeInnovation(const Eigen::MatrixXd& V, const Eigen::VectorXd& h);

// The rank-one candidate (ν+1, (1−β)V + βhh').
NormalisedStatistics RankOneCandidate(const NormalisedStatistics& s, const Eigen::VectorXd& h, double beta);

// Gaussian noise, normal–gamma class ω^{ν/2}exp(−ωνθ̃'Vθ̃/2) w.r.t. ω^{−δ/2}dΘdω [spec §7c].
struct GaussianClass {
  int delta = 1;
  // log γ(β) = 0 at β = 1/(ν+1), and for β < 1/(ν+1) when ξ ≥ 0; −∞ otherwise.
  // log ∫ = log Γ(a) − a log(νD_y/2) + (ρ/2) log(2π/ν) − ½ log|V_z|,  a = (ν−δ−ρ)/2 + 1.
  OneSidedStepResult Evaluate(const NormalisedStatistics& s, const Eigen::VectorXd& h, double beta) const;
  OneSidedStepResult Step(const NormalisedStatistics& s, const Eigen::VectorXd& h) const;  // β = 1/(ν+1)
};

// Student-t (k d.o.f.) noise; k = 1: the paper's Cauchy-tailed class, eq. (39) [spec §2, §7a].
struct StudentClass {
  double k = 1;
  int delta = 1;
  // log γ(β): κ[ν^ν(ν−1)^{1−ν}β(1−β)^{ν−1}] for β ≥ β0, κ log[(1−βr)^ν/(1−r)] below (spec §3, ν = ν(t));
  // log ∫ = log C − (ν−δ−ρ+2)/2 log|V| + (ν−δ−ρ+1)/2 log|V_z|,
  // C = π^{ρ/2} Γ(κν−ρ/2)/Γ(κν) · B((ν−δ−ρ+2)/2, (kν+δ−2)/2) [spec §2].
  OneSidedStepResult Evaluate(const NormalisedStatistics& s, const Eigen::VectorXd& h, double beta) const;
  OneSidedStepResult Step(const NormalisedStatistics& s, const Eigen::VectorXd& h) const;  // cubic root
};

}  // namespace ident::approx
