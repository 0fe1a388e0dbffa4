// Nonparametric maximum-likelihood estimate of a univariate log-concave density, by the active-set
// algorithm of Dümbgen, Hüsler & Rufibach [DHR] ("Active set and EM algorithms for log-concave
// densities based on complete and censored data", arXiv:0707.4643, sec. 3; R: logcondens::logConDens).
//
//   maximise  L(phi) = sum_j w_j phi_j - int exp(phi(x)) dx   over concave phi, linear between the
//   sorted distinct observations x_1 < ... < x_m (weights w_j = multiplicity / n), -inf outside
//   [x_1, x_m]. The maximiser has int exp(phi) = 1, so exp(phi) is the MLE density (Theorem 3.1 of
//   Bassett, Casey & Wets; [DHR] Theorem 2.1). Per segment, int exp(phi) = (x_{j+1} - x_j) J(phi_j, phi_{j+1}),
//   J(r, s) = (e^s - e^r) / (s - r).
//
// Active set: for a knot set S (always containing x_1, x_m) phi is linear between knots, and L is
// maximised over the knot values by Newton's method (tridiagonal Hessian). If the result is not concave
// at a knot, step back along the segment from the previous (concave) phi until a knot becomes linear,
// drop it and repeat. When concave, add the point with the largest directional derivative
//   D_j = int_{x_1}^{x_j} (F_hat - F_n)(r) dr       (direction -(x_j - x)^+, [DHR] eq. (3.2))
// and stop when max_j D_j <= 0. Characterisation ([DHR] Theorem 2.4; checked by CheckKkt):
//   D_j <= 0 for all j,  D_j = 0 at every knot,  int exp(phi) = 1.
//
// The estimated -log density g = -phi is convex piecewise linear (+inf outside [x_1, x_m]); its
// convex conjugate is g*(v) = max_j { v k_j + phi(k_j) } over the knots k_j (exact).
//
// Example:
//   auto mle = ident::approx::FitLogConcaveMle(samples);     // std::vector<double>
//   mle.knots, mle.knot_phi, mle.loglik;                      // as logcondens' knots, phi, L
//   ident::models::Penalty g = mle.NegativeLogDensity();      // for the MAP smoother
#pragma once

#include <functional>
#include <vector>

#include <Eigen/Core>

#include "models/penalties.h"

namespace ident::approx {

struct LogConcaveMleOptions {
  int max_iterations = 10000;  // active-set changes
  double tolerance = 1e-12;    // on D_j (relative to the data range) and on Newton steps
  // Called before each round of knot changes with (round, max_j D_j / range), and with 0 once no D_j is
  // above the tolerance (a progress measure: it falls to the tolerance). Empty: not called.
  std::function<void(int, double)> on_iteration = nullptr;
};

struct LogConcaveMle {
  int n = 0;                    // sample size
  Eigen::VectorXd x;            // sorted distinct sample values x_1 < ... < x_m
  Eigen::VectorXd weights;      // multiplicity / n
  Eigen::VectorXd phi;          // log-density at x
  std::vector<int> knot_index;  // indices into x of the knots (first and last included)
  Eigen::VectorXd knots;        // x at the knots
  Eigen::VectorXd knot_phi;     // phi at the knots
  double loglik = 0;            // sum_{i=1..n} log f_hat(X_i) = n sum_j w_j phi_j
  int iterations = 0;           // active-set changes

  double LogDensity(double t) const;  // -inf outside [x_1, x_m]
  double Cdf(double t) const;
  // g = -phi as a piecewise-linear penalty (+inf outside [x_1, x_m]).
  models::Penalty NegativeLogDensity() const;
  // g*(v) = sup_r { v r - g(r) } = max over knots of v k + phi(k).
  double ConjugateOfNegativeLogDensity(double v) const;
};

// Throws InvalidArgument for fewer than 2 distinct values or non-finite samples.
LogConcaveMle FitLogConcaveMle(const std::vector<double>& samples, const LogConcaveMleOptions& options = {});

// The characterisation of the MLE ([DHR] Theorem 2.4), for tests and reports.
struct LogConcaveKkt {
  double max_directional_derivative = 0;  // max_j D_j (should be <= 0)
  double max_knot_residual = 0;           // max over knots of |D_j|
  double mass_error = 0;                  // |int exp(phi) - 1|
  double max_concavity_violation = 0;     // max positive slope increase at a data point
};
LogConcaveKkt CheckKkt(const LogConcaveMle& mle);

}  // namespace ident::approx
