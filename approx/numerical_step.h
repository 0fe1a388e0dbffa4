// A generic, purely numerical one-sided maximin step for the (ν, V) classes, for ρ ≤ 2 (slow: every evaluated
// β is a minimisation and a nested quadrature; a reference for the tests of the closed-form steps).
//
// Given any noise model log m(h | Θ, ω) and any class shape log s(ν, V; Θ, ω) (w.r.t. ω^{−δ/2}dΘdω),
// the step searches the rank-one family V(β) = (1−β)V + βhh', ν ← ν+1 [spec §3], and for each β computes
//   log γ(β) = min_w [log m(h|w) + log s(ν, V; w) − log s(ν+1, V(β); w)]   by minimisation over w = (Θ, log ω)
//              (coarse grid, then Nelder–Mead from the best grid points; a box |u| ≤ 30 widths, 40 in log ω),
//   log ∫ s(ν+1, V(β)) dμ_δ                                               by nested sinh–sinh quadrature
//              (Boost.Math) over log ω and Θ, centred at Θ̂ and scaled by √(D_y diag V_z⁻¹),
// and maximises log γ + log ∫ over β by a log-spaced grid on (1e−9, 1) and a bracketed Brent search.
// It uses none of the closed forms of spec §3–§5: it exists to verify them (tests/approx) and to try a
// new noise model (say, Laplace) before deriving its class. Accuracy of β: about 1e−7 relative (ρ = 1).
//
// Example:
//   auto log_m = [](const Eigen::VectorXd& h, const Eigen::VectorXd& th, double w) {   // Cauchy
//     const double e = h(0) - th.dot(h.tail(h.size() - 1));
//     return 0.5 * std::log(w) - std::log1p(w * e * e);
//   };
//   auto r = ident::approx::NumericalStep(stats, h, log_m, ident::approx::StudentShape{1.0}, /*delta=*/1);
#pragma once

#include <functional>

#include <Eigen/Core>

#include "approx/one_sided.h"

namespace ident::approx {

using LogModelFn = std::function<double(const Eigen::VectorXd& h, const Eigen::VectorXd& theta, double omega)>;
using LogShapeFn =
    std::function<double(double nu, const Eigen::MatrixXd& V, const Eigen::VectorXd& theta, double omega)>;

// log of ω^{ν/2}(1 + ω θ̃'Vθ̃)^{−κν}, θ̃ = [−1; Θ], κ = (k+1)/2 (the Student / Cauchy class) [spec §2].
struct StudentShape {
  double k = 1;
  double operator()(double nu, const Eigen::MatrixXd& V, const Eigen::VectorXd& theta, double omega) const;
};
// log of ω^{ν/2} exp(−ωνθ̃'Vθ̃/2) (the normal–gamma class) [spec §7c].
struct GaussianShape {
  double operator()(double nu, const Eigen::MatrixXd& V, const Eigen::VectorXd& theta, double omega) const;
};

// log γ and log ∫ of the candidate β, numerically. Throws InvalidArgument for ρ > 2 or bad sizes.
OneSidedStepResult NumericalEvaluate(const NormalisedStatistics& s, const Eigen::VectorXd& h, double beta,
                                     const LogModelFn& log_model, const LogShapeFn& log_shape, int delta);

// The maximin step, numerically.
OneSidedStepResult NumericalStep(const NormalisedStatistics& s, const Eigen::VectorXd& h, const LogModelFn& log_model,
                                 const LogShapeFn& log_shape, int delta);

}  // namespace ident::approx
