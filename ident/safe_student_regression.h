// SafeStudentRegression: the Kárný–Hangos Student-t/Cauchy estimator (ident/student_regression.h)
// with the start-up and lock-in safeguards that `ident` uses by default (issue 3 item 6, docs/kh.md).
//
//   1. Robust data-driven start-up prior (spec §8). The first W = max(20, 4ρ) samples are processed
//      with the provisional prior ν(0) = ρ+k+δ, V(0) = diag(1, 1e−3·I) and kept. Then the estimator
//      restarts from RegressionPrior::FromWindow (Θ0 = 0, σ0 = s_y, P0 = diag((10 s_y/s_{z_i})²)) and
//      replays the window; with `refine_scale` it then takes σ0² = G^{(k+1)/k}·s_e², where s_e is the
//      robust scale (1.4826·MAD) of the window residuals y − Θ̂'z of that fit, restarts once more and
//      replays again (G = scale_growth, see docs/kh.md for the reason of the dof-dependent factor).
//   2. Lock-in monitor and recovery. After start-up, a LockInMonitor watches νβ(t) over the last
//      M = max(100, 20ρ) samples. When more than half of them have νβ < 0.3, the estimator restarts as
//      in 1 from the last max(W, M) samples. Each restart is the exact one-sided recursion (spec §3–§6)
//      from a proper prior over the replayed samples, so the result is a valid one-sided bound of the
//      posterior given those samples (older data are dropped, as with a restarted window).
//   With `base.exact` none of this happens: the spec's recursion with the fixed prior (the --exact option).
//   An explicit `base.prior` switches off 1 (the prior is used as given); 2 stays on.
//
// Update() is O(ρ²) and allocation-free except at the (rare) restarts, which rebuild the estimator and
// replay at most max(W, M) samples (O(Mρ²)).
//
// Example:
//   ident::SafeStudentOptions o;            // Cauchy, δ = 1, safeguards on
//   o.base.dof = 3;                         // Student-t with k = 3
//   ident::SafeStudentRegression est(/*num_parameters=*/4, o);
//   for (...) est.Update(y, z);
//   est.parameters(); est.restarts(); est.monitor().low_fraction();
#pragma once

#include <optional>

#include <Eigen/Core>

#include "ident/common/step_report.h"
#include "ident/lock_in_monitor.h"
#include "ident/regression_estimator.h"
#include "ident/student_regression.h"

namespace ident {

struct SafeStudentOptions {
  StudentRegressionOptions base;  // dof, delta, forgetting, explicit prior, exact
  int startup_window = 0;         // W; 0 = max(20, 4ρ)
  bool refine_scale = true;       // σ0 = scale_factor·s_e from the residuals of the window fit (else s_y)
  // G > 1: D_y(0) = G^{(k+1)/k}·s_e², above the noise scale² (the safe side of spec §8's hazard) by the
  // amount that the recursion's D_y(t) ∝ ν^{−(k+1)/k} decay removes while ν grows G-fold.
  double scale_growth = 4;
  bool restart_on_lock_in = true;
  int lock_in_window = 0;          // M; 0 = max(100, 20ρ)
  double lock_in_threshold = 0.3;  // νβ below this counts as a low weight
};

class SafeStudentRegression {
 public:
  using ParamVector = StudentRegression::ParamVector;

  // Throws InvalidArgument naming the option if `options` is invalid or inadmissible.
  SafeStudentRegression(int num_parameters, const SafeStudentOptions& options = {});

  template <class Derived>
  StepReport Update(double y, const Eigen::MatrixBase<Derived>& z) noexcept {
    const StepReport report = est_->Update(y, z);
    if (options_.base.exact || !report.updated()) return report;
    Store(y, z);
    if (in_startup()) {
      if (count_ == startup_window_) Restart(startup_window_);
    } else if (monitor_.Add(report.nu * report.weight)) {
      ++lock_ins_;
      if (options_.restart_on_lock_in) Restart(capacity());
    }
    return report;
  }

  // True while the start-up window is being collected.
  bool in_startup() const { return startup_window_ > 0 && !started_; }
  // Number of times the monitor flagged a lock-in / restarts made because of it.
  int lock_ins() const { return lock_ins_; }
  int restarts() const { return options_.restart_on_lock_in ? lock_ins_ : 0; }
  const LockInMonitor& monitor() const { return monitor_; }
  // The same for the common interface (ident/regression_estimator.h); nullopt with `base.exact` (no monitor).
  std::optional<LockInStatus> lock_in() const {
    if (options_.base.exact) return std::nullopt;
    return LockInStatus{monitor_.window(), monitor_.threshold(), options_.restart_on_lock_in,
                        lock_ins_,         restarts(),           monitor_.low_fraction()};
  }

  int num_parameters() const { return est_->num_parameters(); }
  const ParamVector& parameters() const { return est_->parameters(); }
  template <class Derived>
  double Predict(const Eigen::MatrixBase<Derived>& z) const {
    return est_->Predict(z);
  }
  Eigen::MatrixXd covariance() const { return est_->covariance(); }
  double nu() const { return est_->nu(); }
  double Dy() const { return est_->Dy(); }
  double noise_std() const { return est_->noise_std(); }
  double beta() const { return est_->beta(); }
  const StudentStepDetails& last_step() const { return est_->last_step(); }
  const RegressionPrior& prior() const { return est_->prior(); }
  const StudentRegression& estimator() const { return *est_; }
  const SafeStudentOptions& options() const { return options_; }
  // Back to the current prior (the data-driven one once start-up is done); clears the monitor.
  void Reset() {
    est_->Reset();
    monitor_.Clear();
  }

 private:
  int capacity() const { return static_cast<int>(buffer_.rows()); }
  template <class Derived>
  void Store(double y, const Eigen::MatrixBase<Derived>& z) noexcept {
    buffer_(next_, 0) = y;
    buffer_.row(next_).tail(num_parameters()) = z.transpose();
    next_ = next_ + 1 == capacity() ? 0 : next_ + 1;
    if (count_ < capacity()) ++count_;
  }
  // Rebuilds the estimator from the robust prior of the last min(n, count_) samples and replays them.
  void Restart(int n) noexcept;
  void Replay(int n) noexcept;

  SafeStudentOptions options_;
  std::optional<StudentRegression> est_;
  int startup_window_ = 0;  // 0 = no start-up (explicit prior or exact)
  bool started_ = false;
  LockInMonitor monitor_;
  Eigen::MatrixXd buffer_;  // ring of the last max(W, M) samples: y, z'
  Eigen::MatrixXd ordered_;  // the same in time order (restart scratch)
  int next_ = 0, count_ = 0, lock_ins_ = 0;
};

}  // namespace ident
