// The threshold sensor's change of reading as one exact log-concave measurement for the log-concave
// Gaussian filter: when y(k−1) ≠ y(k) the information is the wedge of the lagged pair
// s = (s1, s2) = (c'x(k−1), c'x(k)), e.g. s1 < T ≤ s2 for the event 0 → +1 (the first sample past the
// threshold). Under the filter's prediction (x(k−1), x(k)) is jointly Gaussian:
//   x(k−1) ~ N(m⁻, P⁻),  x(k) = A x(k−1) + B u + v:  Cov(x(k), s) = [A P⁻ c, P c],
//   s ~ N((c'm⁻, c'm), [[c'P⁻c, c'A P⁻c], [c'A P⁻c, c'P c]])              (P = A P⁻ A' + P_N)
// The wedge is an intersection of two half-planes, so f_M is log-concave in the augmented state
// (x(k−1), x(k)) [1, sec. IV]; its exact moments are those of a bivariate normal on a quadrant
// (models/truncated_bivariate_normal.h), and x(k) | s is Gaussian, so the update of x(k) is exact
// (BasicLcGaussianFilter::ApplyPairTilt). Unlike a Gaussian reading of x1(k) alone, the wedge also
// informs the velocity: x1(k) − x1(k−1) ≈ h x2 must carry x1 across T within one step.
//
// Regions (y, y_prev ∈ {−1, 0, 1}): a reading y ≠ 0 is s ∈ y·[T, ∞); a reading 0 keeps the bound facing
// the other reading o ≠ 0, s·o < T (its far bound, s·o > −T, has prior mass P(|s| ≥ T on the far side),
// negligible whenever the thresholds are many prior sd apart, and is dropped to keep the region a quadrant).
//
// Example (after f.Predict(model, u), with m_before, P_before the filter's state before it):
//   ident::StepReport r = ident::CorrectReadingChange(f, m_before, P_before, model, sensor, y_prev, y);
//
// Cost: the orthant probability by Owen's T (two owens_t; adaptive quadrature only for a wedge of mass
// < 1e-5) and a few exp/erfc, only at changes of the reading (≈ 2 per event). Fixed-size filters allocate nothing; the
// dynamic one allocates a n × 2 work array.
//
// [1] T. Henningsson, K. J. Åström, "Log-concave Observers", MTNS 2006.
#pragma once

#include <Eigen/Core>

#include "common/step_report.h"
#include "ident/observers/lc_gaussian_filter.h"
#include "models/measurement.h"
#include "models/state_space.h"
#include "models/truncated_bivariate_normal.h"

namespace ident {

// Quadrant {sides_i (s_i − bounds_i) > 0} of the pair (c'x(k−1), c'x(k)) for a change of reading
// y_prev → y of a threshold sensor with threshold T. ok = false if y == y_prev or a reading is not
// −1, 0 or 1.
struct ReadingChangeRegion {
  Eigen::Vector2d bounds, sides;
  bool ok = false;
};
inline ReadingChangeRegion ThresholdChangeRegion(double threshold, double y_prev, double y) {
  auto valid = [](double r) { return r == -1.0 || r == 0.0 || r == 1.0; };
  if (!valid(y_prev) || !valid(y) || y_prev == y) return {};
  ReadingChangeRegion region;
  const double readings[2] = {y_prev, y};
  for (int i = 0; i < 2; ++i) {
    const double r = readings[i], other = readings[1 - i];
    if (r != 0) {
      region.sides(i) = r;  // s ≥ T (r = 1) or s ≤ −T (r = −1)
      region.bounds(i) = r * threshold;
    } else {
      region.sides(i) = -other;  // inside, on the side facing the other reading: s·o < T
      region.bounds(i) = other * threshold;
    }
  }
  region.ok = true;
  return region;
}

// The crossing update of x(k) for the change y_prev → y. `filter` must have been predicted once with
// `model` (and any u) from (mean_before, cov_before). kRejectedInvalid for sizes or readings that do not
// fit; kNumericalFailure (state unchanged) if the wedge has no mass to double precision.
template <int N>
StepReport CorrectReadingChange(BasicLcGaussianFilter<N>& filter, const Eigen::Ref<const Eigen::VectorXd>& mean_before,
                                const Eigen::Ref<const Eigen::MatrixXd>& cov_before,
                                const models::LinearStateSpace& model, const models::ThresholdSensor& sensor,
                                double y_prev, double y) {
  const int n = filter.num_states();
  const auto& c = sensor.c();
  if (mean_before.size() != n || cov_before.rows() != n || cov_before.cols() != n || model.A.rows() != n ||
      model.A.cols() != n || c.size() != n) {
    return {StepStatus::kRejectedInvalid};
  }
  const ReadingChangeRegion region = ThresholdChangeRegion(sensor.threshold(), y_prev, y);
  if (!region.ok) return {StepStatus::kRejectedInvalid};
  Eigen::Matrix<double, N, 2> cross(n, 2);
  Eigen::Matrix<double, N, 1> p_before_c = cov_before * c;
  cross.col(0).noalias() = model.A * p_before_c;     // Cov(x(k), c'x(k−1)) = A P⁻ c
  cross.col(1).noalias() = filter.covariance() * c;  // Cov(x(k), c'x(k))   = P c
  const Eigen::Vector2d prior_mean(c.dot(mean_before), c.dot(filter.mean()));
  Eigen::Matrix2d prior_cov;
  prior_cov << c.dot(p_before_c), c.dot(cross.col(0)), c.dot(cross.col(0)), c.dot(cross.col(1));
  const auto t = models::TruncatedBivariateNormalMoments(prior_mean, prior_cov, region.bounds, region.sides);
  return filter.ApplyPairTilt(cross, prior_mean, prior_cov, t);
}

}  // namespace ident
