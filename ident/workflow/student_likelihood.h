// The Student-t likelihood of residuals with the scale profiled out: the robust order criteria of
// `ident orders --estimator cauchy|student:K` (ident/workflow/polynomial_order_selection.h).
//
// The Student-t_k log-density of a residual r with scale γ (as in Lange, Little & Taylor, "Robust statistical
// modeling using the t distribution", JASA 84, 1989):
//   log p(r | γ) = log Γ((k+1)/2) − log Γ(k/2) − ½ log(kπ) − log γ − (k+1)/2 · log(1 + r²/(kγ²)),
// so the negative log-likelihood of N residuals is
//   NLL_k(γ) = Σ [ (k+1)/2 · log(1 + r_i²/(kγ²)) + log γ ] + N (log Γ(k/2) − log Γ((k+1)/2) + ½ log(kπ)),
// Cauchy being k = 1 (constant N log π). Its derivative in log γ, N − Σ (k+1) r_i²/(kγ² + r_i²), increases
// with γ, so the minimum over γ is the one root of Σ (k+1) r_i²/(kγ² + r_i²) = N (the fixed point of the
// EM scale update γ² = Σ w_i r_i² / N, w_i = (k+1)/(k + r_i²/γ²)); it exists when fewer than a fraction
// k/(k+1) of the residuals are exactly zero.
#pragma once

#include <vector>

namespace ident::workflow {

struct StudentProfile {
  double nll = 0;    // min over γ of NLL_k(γ), constants included
  double scale = 0;  // the minimising γ
};

// NLL_k(γ) of `residuals`. Requires k > 0, γ > 0.
double StudentNegLogLikelihood(const std::vector<double>& residuals, double k, double scale);

// The profile over γ, solved to full double precision (safeguarded Newton in log γ² on a bracket). Throws
// InvalidArgument when no residual is given or too many are exactly zero for a finite minimum.
StudentProfile ProfileStudentLikelihood(const std::vector<double>& residuals, double k);

}  // namespace ident::workflow
