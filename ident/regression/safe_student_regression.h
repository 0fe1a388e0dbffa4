// SafeStudentRegression: the Kárný–Hangos Student-t/Cauchy estimator (ident/regression/student_regression.h) with the
// safeguards that make it robust on data nobody tuned it for. It is what `ident fit --estimator cauchy`
// and the registry's "cauchy"/"student" run, and what an embedding should use (docs/explanation/karny-hangos-estimator.md).
//
//   1. Robust start. The first W = max(20, 4ρ) samples run on the provisional prior ν(0) = ρ+k+δ,
//      V(0) = diag(1, 1e−3·I), or `provisional_v0` in the data's units (the workflow's choice). Then a
//      high-breakdown batch fit of the window (Cauchy maximum likelihood from elemental-subset starts,
//      ident/regression/batch_regression.h, leaving out rows with a regressor beyond five robust scales and
//      rows whose regressor carries a gross output outlier, internal/lagged_output_screen.h) gives Θ_r, and the estimator restarts from the class member of W pseudo-samples centred there
//      (D_y(0) = G^{(k+1)/k}·s_e², s_e the residuals' robust scale) and replays the window.
//      Outliers in y and in the regressors, up to the fit's breakdown point, do not move the start. While
//      the window does not determine every coefficient from its inliers — regressors not identifiable (a
//      record that starts in steady state), more than half of the rows fitted exactly, a direction whose
//      information the fit's outliers carry, or one row alone deciding a direction (weighted leverage
//      above 0.8) — the start waits and is tried again every W samples on the last (up to) 5W.
//   2. Leverage guard (StudentRegressionOptions::leverage_guard): when a sample is grossly mispredicted and
//      its regressor is outlying — some coordinate beyond five robust scales of that coordinate in the
//      last start or restart window, or far out in the metric of the information matrix
//      (z'Ṽ_z⁻¹z > 25 + ρ) — it is read as an outlier, not as new information: its weight adds at most
//      the information of one ordinary sample. A new direction of ordinary values that the model
//      predicts (an input that starts to move) is learnt as the maximin recursion would.
//   3. Lock-in monitor and recovery. A LockInMonitor watches νβ(t) over the last M = max(100, 20ρ)
//      samples; when more than half are below the threshold the estimator restarts as in 1 from the last
//      max(W, M) samples and then replays every sample seen, so the estimate rests on all the data
//      (ν at the end is the number of updates plus ν(0)). A restart that leaves the last window still
//      mostly low-weighted was not a lock-in (the noise is heavier-tailed than the model, or its scale
//      grows along the record, which the replay in time order does not follow); the next restart then
//      waits twice as long. Each restart is recorded (restart_events()).
//   With `base.exact` none of this happens: the spec's recursion with the fixed prior (the --exact option).
//   An explicit `base.prior` switches off 1 (the prior is used as given); 2 and 3 stay on.
//
// The covariance() is StudentRegression's sampling covariance (calibrated whatever the noise law: the
// propagated variance of one pass or the M-estimation sandwich, ident/regression/student_regression.h);
// after BeginPass() the sandwich alone; posterior_covariance() the one-sided posterior's own.
//
// Memory and cost: every updated sample is kept (ρ+1 doubles; `history_limit` caps it, then a restart
// replays the most recent ones and says so). Update() is O(ρ²); it allocates only when the history grows
// (geometrically; `history_reserve` pre-sizes it) and at restarts, which replay the history (O(nρ²)).
//
// Example:
//   ident::SafeStudentOptions o;            // Cauchy, δ = 1, safeguards on
//   o.base.dof = 3;                         // Student-t with k = 3
//   ident::SafeStudentRegression est(/*num_parameters=*/4, o);
//   for (...) est.Update(y, z);
//   est.parameters(); est.covariance(); est.restarts(); est.restart_events();
#pragma once

#include <optional>
#include <vector>

#include <Eigen/Core>

#include "common/step_report.h"
#include "ident/regression/lock_in_monitor.h"
#include "ident/regression/regression_estimator.h"
#include "ident/regression/regression_prior.h"
#include "ident/regression/student_regression.h"

namespace ident {

// The largest lock-in window M (the monitor keeps one flag per sample of the window).
inline constexpr int kMaxLockInWindow = 1'000'000;

struct SafeStudentOptions {
  StudentRegressionOptions base;  // dof, delta, forgetting, explicit prior, exact
  int startup_window = 0;         // W; 0 = max(20, 4ρ)
  bool refine_scale = true;       // σ0 from the residuals of the robust window fit (else s_y)
  // G > 1: D_y(0) = G^{(k+1)/k}·s_e², above the noise scale² (the safe side of spec §8's hazard) by the
  // amount that the recursion's D_y(t) ∝ ν^{−(k+1)/k} decay removes while ν grows G-fold.
  double scale_growth = 4;
  bool restart_on_lock_in = true;
  int lock_in_window = 0;          // M in 2..kMaxLockInWindow; 0 = max(100, 20ρ)
  double lock_in_threshold = 0.3;  // νβ below this counts as a low weight
  long history_limit = 0;          // samples kept for replay; 0 = all
  long history_reserve = 0;        // samples the history is sized for at construction
  // The start-up's provisional prior (ρ+1 square), in place of StudentRegressionOptions::DefaultPrior's
  // diag(1, 1e−3·I), which is in absolute units: the provisional estimate judges the outputs that the
  // workflow cleans before the start, so a prior in the data's own units (DataScaledProvisionalV0) keeps
  // those verdicts the same whatever the units. Ignored with an explicit `base.prior` or `base.exact`.
  std::optional<Eigen::MatrixXd> provisional_v0;
};

// diag(m_0, 1e−3·m_1, …, 1e−3·m_ρ): DefaultPrior's V(0) with each entry in units of the mean square m_i of
// y (i = 0) and of each regressor over the estimation data; nullopt unless every m_i is in [1e−280, 1e280].
std::optional<Eigen::MatrixXd> DataScaledProvisionalV0(const Eigen::VectorXd& mean_squares);

class SafeStudentRegression {
 public:
  using ParamVector = StudentRegression::ParamVector;
  // Robust scales beyond which a regressor coordinate is outlying (the leverage guard and the start-up fit).
  static constexpr double kLeverage = 5;

  // Throws InvalidArgument naming the option if `options` is invalid or inadmissible.
  SafeStudentRegression(int num_parameters, const SafeStudentOptions& options = {});

  template <class Derived>
  StepReport Update(double y, const Eigen::MatrixBase<Derived>& z) noexcept {
    if (!options_.base.exact) est_->set_outlying_regressor(Outlying(z));
    const StepReport report = est_->Update(y, z);
    if (options_.base.exact || !report.updated()) return report;
    Store(y, z);
    if (in_startup()) {
      // Every W samples until the regressors of the last (up to 5W) samples are identifiable.
      if (updates_ % startup_window_ == 0)
        Restart(std::min<long>(stored_, 5L * startup_window_), RestartKind::kStartup);
    } else if (monitor_.Add(report.nu * report.weight)) {
      ++lock_ins_;
      if (options_.restart_on_lock_in && updates_ >= next_restart_) Restart(RecentWindow(), RestartKind::kLockIn);
    }
    return report;
  }

  // True while the start-up window is being collected.
  bool in_startup() const { return startup_window_ > 0 && !started_; }
  // Updates at which the monitor flagged a lock-in / restarts made because of it.
  int lock_ins() const { return lock_ins_; }
  int restarts() const { return static_cast<int>(events_.size()); }
  const std::vector<RestartEvent>& restart_events() const { return events_; }
  const LockInMonitor& monitor() const { return monitor_; }
  // The same for the common interface (ident/regression/regression_estimator.h); nullopt with `base.exact` (no
  // monitor).
  std::optional<LockInStatus> lock_in() const;

  int num_parameters() const { return est_->num_parameters(); }
  const ParamVector& parameters() const { return est_->parameters(); }
  template <class Derived>
  double Predict(const Eigen::MatrixBase<Derived>& z) const {
    return est_->Predict(z);
  }
  // The sampling covariance of Θ̂ (StudentRegression::covariance, a sandwich) and the one-sided
  // posterior's own.
  Eigen::MatrixXd covariance() const { return est_->covariance(); }
  Eigen::MatrixXd posterior_covariance() const { return est_->posterior_covariance(); }
  double nu() const { return est_->nu(); }
  double Dy() const { return est_->Dy(); }
  double noise_std() const { return est_->noise_std(); }
  double beta() const { return est_->beta(); }
  const StudentStepDetails& last_step() const { return est_->last_step(); }
  const RegressionPrior& prior() const { return est_->prior(); }
  const StudentRegression& estimator() const { return *est_; }
  const SafeStudentOptions& options() const { return options_; }
  // Number of samples kept for replay.
  long history_size() const { return stored_; }

  // Another pass over the same samples (AnyRegressionEstimator::BeginPass): the recursion restarts from
  // the current posterior's shape with the weight of ν(0) = ρ+k+δ pseudo-samples — V(0) = V(t), so
  // Θ0 = Θ̂ and D_y(0) = D_y — and the history and monitor are cleared; the caller then feeds the samples
  // again, each weighed against an estimate near the end result. False (state unchanged) with `base.exact`
  // or before any update.
  bool BeginPass();

  // The end of the data while the start-up still waits (a short record, or one whose every window failed
  // the start's checks): starts from the robust fit of every kept sample, with only a rank-deficient
  // window refused, and replays them. True if it started; false (state unchanged) otherwise or when not
  // in the start-up. The command line calls it after the last estimation row.
  bool FinishStartup() noexcept;
  // The end of the data after the start-up: weighs the recursion's estimate against three competing
  // hypotheses, all from the robust fit of every kept sample: a start as the start-up makes one (the fit is
  // the prior of the samples it summarises, ν0 = their number), the same at the fit's own noise scale
  // (without the start-up's safety factor G^{(k+1)/k} on D_y(0)), and a restart as for a lock-in
  // (ν0 = ρ+k+δ), each followed by a replay of every kept sample and kCompetingPasses − 1 further passes
  // (BeginPass). The one with the highest Student-t_k likelihood of the kept samples (scale profiled out)
  // is kept, a hypothesis if it beats the recursion's; an adopted one is recorded
  // (RestartEvent::end_of_data). Samples whose regressor carries a gross output outlier (the fit's
  // lagged-output screen) take no part: the likelihoods leave them out and the hypotheses replay the
  // others alone (RestartEvent::left_out). Up to kMaxCompetingSamples kept samples (the robust fit, made once, costs
  // O(nρ²) per start it tries); none of this with `base.exact` or without restarts. The workflow calls it
  // after FinishStartup when the regressors do not depend on the estimate (not ARMAX/OE).
  bool ReconsiderAtEnd() noexcept;
  static constexpr long kMaxCompetingSamples = 100'000;
  // Passes over the kept samples each competing hypothesis makes (its replay, then BeginPass and a pass).
  static constexpr int kCompetingPasses = 3;

  // Back to the state of a freshly built estimator with the same options: the provisional prior (the
  // explicit one if given), an empty history and a clear monitor.
  void Reset();

 private:
  template <class Derived>
  void Store(double y, const Eigen::MatrixBase<Derived>& z) noexcept {
    ++updates_;
    if (options_.history_limit > 0 && stored_ == options_.history_limit) {  // a ring of the last samples
      history_.col(ring_start_) << y, z;
      ring_start_ = (ring_start_ + 1) % stored_;
      return;
    }
    if (stored_ == history_.cols()) Grow();
    history_.col(stored_++) << y, z;
  }
  void Grow() noexcept;
  // Some coordinate of z beyond kLeverage robust scales of its column in the last (re)start window.
  template <class Derived>
  bool Outlying(const Eigen::MatrixBase<Derived>& z) const noexcept {
    if (!started_ || centre_.size() != z.size()) return false;
    for (Eigen::Index i = 0; i < z.size(); ++i)
      if (std::abs(z(i) - centre_(i)) > kLeverage * spread_(i)) return true;
    return false;
  }
  long RecentWindow() const;
  // Column i (0 = oldest) of the kept samples.
  Eigen::Index Column(long i) const { return (ring_start_ + i) % stored_; }
  // What a Restart is for; it sets the prior's weight ν0 (see Restart in the .cc).
  enum class RestartKind {
    kStartup,    // the robust start: the window's fit is the prior of its samples (ν0 = the window)
    kLockIn,     // a lock-in restart: ν0 = ρ+k+δ pseudo-samples at the recent fit (recorded)
    kEndOfData,  // ReconsiderAtEnd's competing start: as kStartup over every kept sample (recorded)
  };
  // The robust fit of the last `recent` samples (their rows, oldest first): the prior of a start from it
  // with weight ν0 (nullopt: the window has none, see RobustWindowPrior in the .cc), each sample's influence
  // on it, and the regressors' median and robust scale (the leverage guard's reference).
  struct WindowStart {
    Eigen::MatrixXd window;
    Eigen::Array<bool, Eigen::Dynamic, 1> poisoned;  // rows whose regressor carries a gross output outlier
    Eigen::VectorXd centre, spread, influence;
    std::optional<RegressionPrior> prior;
    double seed = 0;
  };
  double StartWeight(RestartKind kind, long recent) const;
  // `strict` = false: FinishStartup's start from every kept sample (see RobustWindowPrior).
  WindowStart FitWindow(long recent, double nu0, bool strict) const;
  // Rebuilds the estimator from the robust fit of the last `recent` samples and replays every kept sample.
  void Restart(long recent, RestartKind kind, bool strict = true) noexcept;
  // Rebuilds the estimator from `start` (the vague prior of its window if it has none) and replays every
  // kept sample; a restart other than the start-up is recorded.
  void StartFrom(WindowStart start, RestartKind kind) noexcept;
  // Replays every kept sample into est_ (the last M weights refill the monitor).
  void Replay() noexcept;
  // (y − Θ'z)² of every kept sample, oldest first.
  Eigen::ArrayXd KeptSquaredResiduals(const Eigen::VectorXd& theta) const;
  // Student-t_k NLL of the kept samples at Θ but those `left_out` (one flag per kept sample, oldest first),
  // scale at its ML value (constants dropped).
  double ProfileNegativeLogLikelihood(const Eigen::VectorXd& theta,
                                      const Eigen::Array<bool, Eigen::Dynamic, 1>& left_out) const;
  // Student-t_k NLL of residuals r given as r² (scale at its ML value, constants dropped).
  double NegativeLogLikelihood(const Eigen::ArrayXd& r2) const;
  bool CompeteWithRobustRestart() noexcept;
  // Removes the kept samples marked in `left_out` (one flag per kept sample, oldest first) from the history, so
  // that a restart replays the others alone. False (nothing removed) unless some are marked and at least
  // 2ρ+2 samples remain.
  bool LeaveOut(const Eigen::Array<bool, Eigen::Dynamic, 1>& left_out);
  // The same rows out of a window's start (its window rows and their influence on the fit).
  static void LeaveOut(WindowStart& start, const Eigen::Array<bool, Eigen::Dynamic, 1>& left_out);

  SafeStudentOptions options_;
  std::optional<StudentRegression> est_;
  int startup_window_ = 0;  // 0 = no start-up (explicit prior or exact)
  bool started_ = false;
  LockInMonitor monitor_;
  Eigen::MatrixXd history_;          // (ρ+1) x capacity: y, z of every updated sample (column = sample)
  Eigen::VectorXd start_influence_;  // influence of the last (re)start window's samples on its fit
  Eigen::VectorXd centre_, spread_;  // median and robust scale of each regressor in the last (re)start window
  long stored_ = 0, ring_start_ = 0, updates_ = 0, next_restart_ = 0, backoff_ = 1;
  long left_out_ = 0;  // updates no longer kept because LeaveOut removed them (not the history limit)
  int lock_ins_ = 0;
  int pass_ = 1;  // RestartEvent::pass
  std::vector<RestartEvent> events_;
  long start_update_ = 0, start_window_ = 0;  // the robust start (LockInStatus)
  bool start_at_end_ = false;
};

}  // namespace ident
