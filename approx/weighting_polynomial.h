// The weighting polynomial of the Kárný–Hangos one-sided maximin step for Student-t / Cauchy
// regression: the cubic whose root is the data weight β(t), its bracket, the objective log H0 and the
// deterministic, always-bracketed root selection of spec §5.
//
//   Problem at step t: ν = ν(t) (after forgetting and the +1), ρ, k (dof), δ ∈ {0,1}, and
//   ξ = 1 − h'Ṽ⁻¹h ≤ ξ_z = 1 − z'Ṽ_z⁻¹z ≤ 1                                          [spec §3]
//
//   log H0(β) = κ[log β + (ν−1) log(1−β)] − (n+1)/2 log(1−β)
//               − (n−ρ+2)/2 log(1−βξ) + (n−ρ+1)/2 log(1−βξ_z),   κ = (k+1)/2, n = ν−δ   [spec §3]
//   P(β) = μ0 + μ1β + μ2β² + μ3β³ = (2 d log H0/dβ)·β(1−β)(1−βξ)(1−βξ_z)                [spec §4]
//     μ0 = k+1
//     μ1 = −(kν+δ−1) + (ν−δ−ρ+1−k)ξ − (ν−δ−ρ+2+k)ξ_z
//     μ2 = ((k−1)ν+2δ+ρ−3)ξ + ((k+1)ν−ρ)ξ_z + kξξ_z     (paper (46)/(106) misprints the ξ_z sign)
//     μ3 = (2−kν−δ)ξξ_z
//   Bracket: β0 = 1/(ν − (ν−1)min(0, ξ)),  β_hi = (k+1)/(kν+δ−2)                           [spec §4]
//   Admissible iff ν > ν_hard = max(ρ+δ−1, (k+3−δ)/k, ρ/(k+1))                              [spec §5]
//
// SolveWeightReference() is the algorithm of spec §5 as printed: split [β0, β_hi] at the real roots of
// P', find every sign change (+ → −) of P on the monotone pieces by safeguarded Newton (bisection
// whenever a step leaves the bracket, stop when |Δβ| ≤ 4e−16·β), and return the candidate with the
// largest log H0. SolveWeight() returns the same maximin root in fewer iterations — it is the estimators'
// hot path, and bench/weight_benchmark.cc times the two against each other. What makes it faster:
//
//   * a bound on P' over [0, β_hi] or, failing that, a sign test on P' and P'' at the bracket ends (no
//     square root) proves in the usual case that P decreases on [β0, β_hi], so the root is unique and
//     log H0 is never evaluated; otherwise the pieces of spec §5 are formed and compared exactly as in
//     the reference. That usual case is approx/weight_fast_path.h, inline for the estimators
//     (SolveWeightInline: the same bits as SolveWeight);
//   * on each piece: Householder's step of order 3 (quartic convergence; P is a cubic, so its Taylor
//     series is exact), started at that same step taken from β = 0 (the root is O(1/ν): accurate to
//     O(1/ν³) with no Horner and one division) or, if that lies outside, at the large-ν asymptote of
//     spec §7a; inside a bracket [a, b] with P(a) > 0 > P(b) that shrinks at every iterate; bisection
//     whenever a step leaves it; no unbracketed step, no Cardano;
//   * it stops when the step's own error estimate K·Δβ⁴ (or the step) is below 1e−16·β, i.e. at the
//     accuracy the reference reaches (and the recursion needs: β enters V(t) = (1−β)Ṽ + βhh', and the
//     spec's vectors are checked to 1e−9), without the reference's last confirming iteration.
//   Tests (tests/approx/weight_solver_test.cc): agreement with the reference to 1e−12 relative on 1.2·10⁵
//   random problems wherever the root is well conditioned, and with a long-double root of the same cubic
//   to within the rounding floor 16ε·cond where it is not (β → 1 as ν → ν_hard).
// Neither allocates.
//
// Example:
//   ident::approx::WeightingProblem p{.nu = 7, .xi = -3.2, .xi_z = 0.4, .rho = 4, .k = 1, .delta = 1};
//   ident::approx::WeightSolution s = ident::approx::SolveWeight(p);   // s.beta ∈ [s.beta0, s.beta_hi]
#pragma once

#include <array>

namespace ident::approx {

struct WeightingProblem {
  double nu = 0;    // ν(t): the forgotten ν(t−1) plus one
  double xi = 0;    // ξ   = 1 − h'Ṽ⁻¹h
  double xi_z = 0;  // ξ_z = 1 − z'Ṽ_z⁻¹z
  int rho = 1;      // number of parameters ρ
  double k = 1;     // Student-t degrees of freedom (1 = Cauchy)
  int delta = 1;    // ω-exponent convention δ ∈ {0, 1} [spec §2.1]
};

struct WeightSolution {
  double beta = 0;              // the maximin weight β(t)
  double beta0 = 0;             // lower end of the bracket
  double beta_hi = 0;           // upper end of the bracket
  int num_maxima = 0;           // local maxima of H0 found in the bracket (2 = "new information or outlier?")
  double smallest_maximum = 0;  // when num_maxima > 1: the smallest of their β (the outlier reading)
  bool ok = true;               // false only if no candidate could be found (not observed for ν > ν_hard)
  int iterations = 0;           // root-finder iterations (P evaluations inside the pieces), for benchmarks
};

// ν_hard = max(ρ+δ−1, (k+3−δ)/k, ρ/(k+1)) [spec §5]; every step needs ν(t) > ν_hard.
double NuHard(int rho, double k, int delta);
// ν_robust = ρ+k+δ−1: above it a gross outlier gets a vanishing weight [spec §5].
double NuRobust(int rho, double k, int delta);

double Beta0(const WeightingProblem& p);   // 1/(ν − (ν−1)min(0, ξ))
double BetaHi(const WeightingProblem& p);  // (k+1)/(kν+δ−2)

// μ0..μ3 of spec §4 (unscaled).
std::array<double, 4> WeightingCoefficients(const WeightingProblem& p);

// ê·dβ/dê for a root β of P(β; ξ, ξ_z) [spec §4] as the prediction error ê moves with ξ_z fixed:
// P_β·dβ + P_ξ·dξ = 0 and ξ = ξ_z − ê²/D_y give 2u·P_ξ/P_β, u = ξ_z − ξ = ê²/D_y. For large ν, ν·β is the
// EM weight (k+1)/(k+u) and ν·(β + ê·dβ/dê) the slope ψ' of the Student-t score ψ = w·ê.
double WeightElasticity(const WeightingProblem& p, double beta);

// log H0(β) (with log1p), valid on the branch β ≥ β0.
double LogH0(const WeightingProblem& p, double beta);

// The full maximin objective log H(β) on (0, 1), both branches of spec §3 (β < β0 uses the
// boundary value of the essinf). For tests and for the grid checks; up to the same additive constant as LogH0.
double LogHFull(const WeightingProblem& p, double beta);

// β(t), the maximin root of spec §5, fast (see above). Requires ν > ν_hard (not checked here: the
// estimator refuses such configurations at construction).
WeightSolution SolveWeight(const WeightingProblem& p);

// β(t) by the algorithm of spec §5 exactly as printed: the oracle for SolveWeight in tests and benchmarks.
WeightSolution SolveWeightReference(const WeightingProblem& p);

}  // namespace ident::approx
