// The convergence measure of an expectation-propagation site refit, shared by the fixed-lag excursion
// reading (studies/mems/excursion_reading.h) and the sliding-window filter (studies/mems/window_ep_filter.h).
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Core>

namespace ident::internal {

// How far a site's tilted moments (mean mt, covariance vt over its first `dim` ≤ 2 coordinates) moved since
// the last refit, relative to their scale: max_i |Δmean_i|/sd_i and |Δvar_i|/var_i; +inf at the first refit
// (last_mean NaN). Records (mt, vt) as the last refit's moments.
inline double RecordTiltedChange(const Eigen::Vector2d& mt, const Eigen::Matrix2d& vt, int dim,
                                 Eigen::Vector2d& last_mean, Eigen::Matrix2d& last_cov) {
  double change = std::isfinite(last_mean(0)) ? 0.0 : std::numeric_limits<double>::infinity();
  for (int i = 0; i < dim; ++i) {
    const double sd = std::sqrt(std::max(vt(i, i), 1e-300));
    change = std::max(change, std::abs(mt(i) - last_mean(i)) / sd);
    change = std::max(change, std::abs(vt(i, i) - last_cov(i, i)) / std::max(vt(i, i), 1e-300));
  }
  last_mean = mt;
  last_cov = vt;
  return change;
}

}  // namespace ident::internal
