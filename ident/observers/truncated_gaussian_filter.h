// Assumed-density filter in the family of Gaussians restricted to the current reading's interval, for a
// 2-state model read by a threshold sensor (the MEMS case of [1, sec. V]).
//
// Why: the Gaussian filters of this library (lc_plain, and the sites of lc_window's EP) replace the hard
// edge of an interval reading by a Gaussian, and the next, strongly dependent reading truncates that
// Gaussian again (lc_plain's collapse), or — in EP — many nearly redundant Gaussian sites each count part
// of the same truncation (Cunningham, Hennig & Lacoste-Julien 2011): lc_window's velocity variance is
// ≈ 0.82 of the converged grid's after long runs of unchanged y = 0 (docs/explanation/observers.md). Here the
// hard edge of the *current* reading is kept exactly in the approximating family, so a repeated reading
// only removes the mass that actually left the interval in one step; no Gaussian site stands in for it.
//
// Family. q_k(x) ∝ N(x; m_k, P_k) · 1{c'x ∈ R(y(k))}, R(0) = (−T, T), R(±1) = ±[T, ∞): the "parent"
// N(m, P) and the reading's interval (before the first reading: no restriction). (The exponential family of
// densities ∝ exp(θ'x − ½ x'Λx) on the half-space/strip, sufficient statistics x, xx'; its KL projection
// is moment matching, Minka 2001.)
//
// Step k (u = u(k−1), y = y(k)), exact up to the projection:
//   1. Under the parent, (x(k−1), x(k)) is jointly Gaussian: x(k) = A x(k−1) + B u + w, w ~ N(0, P_N).
//      With s = (c'x(k−1), c'x(k)): μ_s = (c'm, c'm⁻), Σ_s = [[c'Pc, c'PA'c], [·, c'P⁻c]],
//      m⁻ = A m + B u, P⁻ = A P A' + P_N, Cov(x(k), s) = [A P c, P⁻ c].
//   2. The exact density of x(k) given q_{k−1} and the reading y(k) is the marginal of that Gaussian
//      restricted to s ∈ R(y(k−1)) × R(y(k)) (a rectangle, quadrant or wedge; the previous reading's
//      restriction is part of q_{k−1}). Its moments: the bivariate truncated-normal moments (μ_t, V_t) of s
//      on the rectangle (Tallis 1961, by inclusion–exclusion of quadrants, or one quadrant), and x(k) | s
//      Gaussian: m_x = m⁻ + K(μ_t − μ_s), P_x = P⁻ − K(Σ_s − V_t)K', K = Cov(x(k), s) Σ_s⁻¹.
//      (m_x, P_x) is the filter's read-out (mean(), covariance()).
//   3. Projection onto the family with the interval R(y(k)): the parent (m', P') whose restriction to
//      c'x ∈ R has the moments (m_x, P_x). The restriction acts on s = c'x only, and x | s is the same under
//      parent and restriction, so: the 1-D truncated normal N(a, v) on R with mean c'm_x and variance
//      c'P_x c (a, v by Newton's method; unique because the truncated normal on a fixed interval is a
//      regular exponential family in (a/v, −1/(2v))), g = P_x c / (c'P_x c), P' = (P_x − g g' c'P_x c) +
//      g g' v, m' = m_x − g (c'm_x − a).
// Step 2 is the only place where information enters and it is exact; the only approximation is step 3:
// the true density of x(k) (a Gaussian on the rectangle pushed forward) is replaced by the closest member
// of the family (a Gaussian on the current interval). Nothing is tuned: no window, no σ_o.
//
// A target outside the family's moment space (possible on a bounded interval only: a restricted density
// flatter than the uniform) has no parent with positive variance; the step then keeps the target's
// moments as read-out and sets the parent's variance along c to the largest value the Newton iteration
// reached (counted in projection_failures()).
//
// With the model given at construction it is a StateObserver (ident/observers/state_observer.h): Update(d) =
// Step(model, d.u, d.y); the registry builds it as "lc_truncated" (ident/registry/observer_registry.h).
//
// Example:
//   ident::TruncatedGaussianFilter f(sensor, m0, P0);
//   for (...) { f.Step(model, u, y); use(f.mean(), f.covariance()); }   // u = u(k−1), y = y(k)
//   ident::TruncatedGaussianFilter g(model, sensor, m0, P0);
//   for (const auto& d : items) g.Update(d);                            // d = (u(k−1), y(k))
//
// [1] T. Henningsson, K. J. Åström, "Log-concave Observers", MTNS 2006.
// [2] T. P. Minka, "A family of algorithms for approximate Bayesian inference", PhD thesis, MIT, 2001 (ADF).
#pragma once

#include <Eigen/Core>

#include "common/step_report.h"
#include "ident/observers/state_observer.h"
#include "models/measurement.h"
#include "models/state_space.h"

namespace ident {

// Moments of N(mean, covariance) restricted to the rectangle lo(i) < s_i < hi(i) (lo may be −∞, hi +∞).
// Bounds farther than 9 sd from the mean are dropped (mass beyond < 1.2e-19); if then at most one bound per
// coordinate is left, this is one Tallis quadrant (models/truncated_bivariate_normal.h, accurate far into
// the tails); otherwise inclusion–exclusion of the four quadrants' unnormalised moments, accurate in
// absolute terms (≈ 1e-15 of the Gaussian's mass): ok = false if the rectangle's mass is below 1e-8 there.
struct RectangleMoments {
  double log_probability = 0;
  Eigen::Vector2d mean;
  Eigen::Matrix2d covariance;
  bool ok = false;
};
RectangleMoments TruncatedBivariateRectangleMoments(const Eigen::Vector2d& mean, const Eigen::Matrix2d& covariance,
                                                    const Eigen::Vector2d& lo, const Eigen::Vector2d& hi);

// The N(a, v) whose restriction to (lo, hi) has mean `mean` and variance `variance` (Newton's method on
// (a, log √v) from (mean, variance)); false if none is found (a target outside the family's moment space).
bool InvertTruncatedNormalMoments(double mean, double variance, double lo, double hi, double& a, double& v);

class TruncatedGaussianFilter {
 public:
  // Throws InvalidArgument for a sensor that is not on 2 states or a prior that is not finite / symmetric
  // positive definite.
  TruncatedGaussianFilter(const models::ThresholdSensor& sensor, const Eigen::Vector2d& mean,
                          const Eigen::Matrix2d& covariance);
  // With a stored model for Update(); also throws InvalidArgument for a model that is invalid or not 2-state.
  TruncatedGaussianFilter(models::LinearStateSpace model, const models::ThresholdSensor& sensor,
                          const Eigen::Vector2d& mean, const Eigen::Matrix2d& covariance);

  // One step: time update with u = u(k−1), then the reading y = y(k) ∈ {−1, 0, 1}. kRejectedInvalid (state
  // unchanged) for a model that is not 2-state, u of the wrong size or not finite, or an invalid reading.
  // A reading with no mass under the approximation (rectangle mass below the floor) leaves the filter at
  // the prediction restricted to nothing new (parent = predicted parent, interval = the new reading's) and is
  // counted in failures(); the step is still kUpdated.
  StepReport Step(const models::LinearStateSpace& model, const Eigen::Ref<const Eigen::VectorXd>& u, double y);
  // Step with the stored model (second constructor); kRejectedInvalid without one.
  StepReport Update(const StateSpaceItem& item);

  const Eigen::Vector2d& mean() const { return mean_; }  // moments of q_k (read-out)
  const Eigen::Matrix2d& covariance() const { return cov_; }
  const Eigen::Vector2d& parent_mean() const { return pm_; }  // parent N(m, P) of q_k
  const Eigen::Matrix2d& parent_covariance() const { return pP_; }
  long failures() const { return failures_; }
  long projection_failures() const { return projection_failures_; }

 private:
  Eigen::Vector2d c_;
  double threshold_ = 0;
  Eigen::Vector2d pm_, mean_;
  Eigen::Matrix2d pP_, cov_;
  double lo_, hi_;  // interval of the current reading (−∞, ∞ before the first)
  long failures_ = 0, projection_failures_ = 0;
  bool has_model_ = false;  // stored model for Update()
  models::LinearStateSpace model_;
};

}  // namespace ident
