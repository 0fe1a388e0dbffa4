#include "ident/safe_student_regression.h"

#include <algorithm>
#include <cmath>

namespace ident {
namespace {

StudentRegressionOptions Plain(StudentRegressionOptions o) {
  if (!o.exact && !o.prior) o.exact = true;  // the provisional prior, without the estimator's own start-up rule
  return o;
}

int DefaultMonitorWindow(const SafeStudentOptions& o, int rho) {
  IDENT_REQUIRE(o.lock_in_window == 0 || o.lock_in_window >= 2, "lock_in_window = {}; need 0 (automatic) or >= 2",
                o.lock_in_window);
  return o.lock_in_window > 0 ? o.lock_in_window : std::max(100, 20 * std::max(rho, 1));
}

}  // namespace

SafeStudentRegression::SafeStudentRegression(int num_parameters, const SafeStudentOptions& options)
    : options_(options),
      est_(std::in_place, num_parameters, Plain(options.base)),
      monitor_(DefaultMonitorWindow(options, num_parameters), options.lock_in_threshold) {
  IDENT_REQUIRE(std::isfinite(options.scale_growth) && options.scale_growth >= 1,
                "scale_growth = {}; need a finite G >= 1", options.scale_growth);
  // νβ ≈ (k+1)/(k + ê²/D_y) [spec §7a]: (k+1)/k for a sample the model fits exactly, so a threshold at or
  // above it would count every sample as low and restart every M samples.
  const double k = options.base.dof, top = (k + 1) / k;
  IDENT_REQUIRE(options.lock_in_threshold < top,
                "lock-in threshold = {}; need 0 < threshold < (k+1)/k = {} (the weight nu*beta of a sample fitted "
                "exactly)", options.lock_in_threshold, top);
  IDENT_REQUIRE(options.startup_window == 0 || options.startup_window >= 2,
                "startup_window = {}; need 0 (automatic) or at least 2 samples", options.startup_window);
  if (options_.base.exact) return;
  if (!options_.base.prior)
    startup_window_ = options_.startup_window > 0 ? options_.startup_window : std::max(20, 4 * num_parameters);
  buffer_.resize(std::max(startup_window_, monitor_.window()), num_parameters + 1);
  ordered_.resizeLike(buffer_);
}

void SafeStudentRegression::Replay(int n) noexcept {
  const int rho = num_parameters();
  for (int t = 0; t < n; ++t) est_->Update(ordered_(t, 0), ordered_.row(t).tail(rho).transpose());
}

void SafeStudentRegression::Restart(int n) noexcept {
  n = std::min(n, count_);
  const int rho = num_parameters();
  for (int t = 0; t < n; ++t) ordered_.row(t) = buffer_.row((next_ - n + t + capacity()) % capacity());
  StudentRegressionOptions o = options_.base;
  const double nu0 = rho + o.dof + o.delta;  // spec §8 default ν(0)
  try {
    o.prior = RegressionPrior::FromWindow(ordered_.topRows(n), nu0, o.delta);  // σ0 = s_y
    est_ = StudentRegression(rho, o);  // assigned only if the constructor succeeds
    Replay(n);
    if (options_.refine_scale) {
      // σ0 = robust scale of the residuals of the window fit (overestimates the noise while Θ̂ is rough).
      const Eigen::VectorXd residuals =
          ordered_.col(0).head(n) - ordered_.topRows(n).rightCols(rho) * est_->parameters();
      o.prior = RegressionPrior::FromWindow(ordered_.topRows(n), nu0, o.delta,
                                             std::pow(options_.scale_growth, (o.dof + 1) / (2 * o.dof)) * RobustScale(residuals));
      est_ = StudentRegression(rho, o);
      Replay(n);
    }
  } catch (...) {
    // Cannot happen: the window is finite and the prior diagonal positive; keep the current estimator.
  }
  started_ = true;
  monitor_.Clear();
}

}  // namespace ident
