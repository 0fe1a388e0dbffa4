// The common interface of ident's recursive regression estimators.
//
// A regression data item is d(t) = (y(t), z(t)): the output and the regressor (ρ entries).
//
// Compile time: the concept RegressionEstimator. Every estimator E provides
//   StepReport E::Update(double y, z)     one sample; O(ρ²); allocation-free; never throws
//   int        num_parameters()           ρ
//   parameters()                          Θ̂ (ρ-vector), valid at any time
//   Eigen::MatrixXd covariance()          covariance of Θ̂ (O(ρ³), allocates; not for the hot path)
//   double     Predict(z)                 one-step prediction Θ̂'z
//   double     nu(), Dy()                 sample count ν(t) and residual dispersion D_y
//   double     noise_std()                estimated noise standard deviation (or scale)
//   void       Reset()                    back to the prior
// and optionally
//   std::optional<LockInStatus> lock_in() the lock-in safeguard's state, if the estimator has one
//
// Run time: AnyRegressionEstimator is the regression side of the one estimator interface
// (common/estimator.h: Update(RegressionItem), mean() = Θ̂, Predict(RegressionItem) = Θ̂'z); RegressionEstimatorModel
// wraps any such E, and MakeEstimator() / MakeRegressionEstimator() build one by name ("rls", "cauchy",
// "student:3", ...) from EstimatorSettings (ident/registry/estimator_registry.h).
#pragma once

#include <concepts>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "common/estimator.h"
#include "common/step_report.h"

namespace ident {

template <class E>
concept RegressionEstimator = requires(E& e, const E& ce, double y, const Eigen::VectorXd& z) {
  { e.Update(y, z) } -> std::same_as<StepReport>;
  { ce.num_parameters() } -> std::convertible_to<int>;
  { ce.parameters() } -> std::convertible_to<Eigen::VectorXd>;
  { ce.covariance() } -> std::convertible_to<Eigen::MatrixXd>;
  { ce.Predict(z) } -> std::convertible_to<double>;
  { ce.nu() } -> std::convertible_to<double>;
  { ce.Dy() } -> std::convertible_to<double>;
  { ce.noise_std() } -> std::convertible_to<double>;
  {e.Reset()};
};

// One restart of a robust estimator's lock-in safeguard (ident/regression/safe_student_regression.h).
struct RestartEvent {
  long update = 0;               // the update (1-based) at which the monitor flagged the lock-in
  long replayed = 0;             // samples the restarted estimator was run on (all kept samples)
  long dropped = 0;              // samples seen but no longer kept (history limit), not replayed
  long left_out = 0;             // samples not replayed because their regressor carries a gross output outlier
                                 // (an end-of-data restart's lagged-output screen)
  double low_weight_before = 0;  // share of the monitor window with νβ < threshold, at the flag
  double low_weight_after = 0;   // the same over the last window of the replay
  bool resolved = true;          // false: still more than half low after the replay (heavy tails, not
                                 // a lock-in); the next restart then waits twice as long
  bool end_of_data = false;      // made when the data ended: the restart's estimate had the higher likelihood
                                 // (SafeStudentRegression::ReconsiderAtEnd)
  int pass = 1;                  // the pass over the data it was made in (1 = the first; BeginPass starts
                                 // the next, as do the further passes of an end-of-data restart)
};

// The state of a robust estimator's lock-in safeguard (ident/regression/lock_in_monitor.h, docs/explanation/karny-hangos-estimator.md):
// the monitor flags a lock-in when more than half of the last `window` updated samples had a normalised
// weight νβ below `threshold`; with `restart` the estimator then restarts from the recent samples.
struct LockInStatus {
  int window = 0;                    // M, samples watched
  double threshold = 0;              // νβ below this counts as a low weight
  bool restart = true;               // restart when flagged (else: flag only)
  int flagged = 0;                   // updates at which the monitor was flagged (without restart: every
                                     // update of a lasting lock-in; with restart: each one restarts)
  int restarts = 0;                  // restarts made because of it
  double low_weight_fraction = 0;    // share of the current window with νβ < threshold
  std::vector<RestartEvent> events;  // one per restart, in order
  // The robust start: the update after which it was made (0: none, the prior was given) and the samples
  // its window fit used; `start_at_end`: made when the data ended (FinishStartup), from every sample.
  long start_update = 0;
  long start_window = 0;
  bool start_at_end = false;
};

// Type-erased regression estimator for selection at run time: the regression side of AnyEstimator.
class AnyRegressionEstimator : public AnyEstimator {
 public:
  using AnyEstimator::Predict;
  using AnyEstimator::Update;
  ItemKind item_kind() const final { return ItemKind::kRegression; }
  int dimension() const final { return num_parameters(); }
  StepReport Update(const RegressionItem& item) final { return Update(item.y, item.z); }
  Eigen::VectorXd mean() const final { return parameters(); }
  double Predict(const RegressionItem& item) const final { return Predict(item.z); }

  virtual StepReport Update(double y, const Eigen::Ref<const Eigen::VectorXd>& z) = 0;
  virtual int num_parameters() const = 0;
  virtual Eigen::VectorXd parameters() const = 0;
  virtual Eigen::MatrixXd covariance() const = 0;
  virtual double Predict(const Eigen::Ref<const Eigen::VectorXd>& z) const = 0;
  virtual double nu() const = 0;
  virtual double Dy() const = 0;
  // Estimated noise standard deviation (for RLS s; for Student-t/Cauchy the scale σ ≈ √D_y).
  virtual double noise_std() const = 0;
  // The lock-in safeguard's state; nullopt for estimators without one (RLS, --exact).
  virtual std::optional<LockInStatus> lock_in() const { return std::nullopt; }
  // The restarts lock_in() lists, counted without copying them (0 for estimators without the safeguard).
  virtual long restarts() const { return 0; }
  // True if the estimator weighs samples by their fit (its steps' weights can flag outliers), false if
  // every sample counts alike (least squares) or it reports no per-sample weights (batch).
  virtual bool judges_outliers() const { return false; }
  // True while a data-driven start-up is still collecting its window: the estimate is the prior's.
  virtual bool in_startup() const { return false; }
  // "recursive" (one O(ρ²) update per sample) or "batch" (solves on all samples at read-out).
  virtual std::string kind() const { return "recursive"; }
  // Prepares another pass over the same samples, which the caller then feeds again from the first:
  // the estimator restarts from a prior centred at its current estimate. False (state unchanged) where a
  // further pass cannot change the result (RLS and the batch estimators reach their optimum in one pass).
  virtual bool BeginPass() { return false; }
  // The data have ended while a data-driven start-up still waits: start from every sample seen
  // (SafeStudentRegression::FinishStartup). False where there is no start-up or it cannot start.
  virtual bool FinishStartup() { return false; }
  // The data have ended: weigh the estimate against a competing hypothesis and keep the likelier
  // (SafeStudentRegression::ReconsiderAtEnd). Only for regressors that do not depend on the estimate
  // (its kept samples are replayed). False where there is none or the estimate stays.
  virtual bool ReconsiderAtEnd() { return false; }
};

// Adapter: wraps a concrete estimator E.
template <RegressionEstimator E>
class RegressionEstimatorModel final : public AnyRegressionEstimator {
 public:
  template <class... Args>
  explicit RegressionEstimatorModel(std::string name, Args&&... args)
      : name_(std::move(name)), e_(std::forward<Args>(args)...) {}
  std::string name() const override { return name_; }
  StepReport Update(double y, const Eigen::Ref<const Eigen::VectorXd>& z) override { return e_.Update(y, z); }
  int num_parameters() const override { return e_.num_parameters(); }
  Eigen::VectorXd parameters() const override { return e_.parameters(); }
  Eigen::MatrixXd covariance() const override { return e_.covariance(); }
  double Predict(const Eigen::Ref<const Eigen::VectorXd>& z) const override { return e_.Predict(z); }
  double nu() const override { return e_.nu(); }
  double Dy() const override { return e_.Dy(); }
  double noise_std() const override { return e_.noise_std(); }
  void Reset() override { e_.Reset(); }
  std::optional<LockInStatus> lock_in() const override {
    if constexpr (requires { e_.lock_in(); })
      return e_.lock_in();
    else
      return std::nullopt;
  }
  long restarts() const override {
    if constexpr (requires { e_.restarts(); })
      return e_.restarts();
    else
      return 0;
  }
  bool judges_outliers() const override {
    if constexpr (requires { e_.judges_outliers(); })
      return e_.judges_outliers();
    else
      return requires { e_.lock_in(); };
  }
  bool in_startup() const override {
    if constexpr (requires { e_.in_startup(); })
      return e_.in_startup();
    else
      return false;
  }
  std::string kind() const override {
    if constexpr (requires { e_.kind(); })
      return e_.kind();
    else
      return "recursive";
  }
  bool BeginPass() override {
    if constexpr (requires { e_.BeginPass(); })
      return e_.BeginPass();
    else
      return false;
  }
  bool FinishStartup() override {
    if constexpr (requires { e_.FinishStartup(); })
      return e_.FinishStartup();
    else
      return false;
  }
  bool ReconsiderAtEnd() override {
    if constexpr (requires { e_.ReconsiderAtEnd(); })
      return e_.ReconsiderAtEnd();
    else
      return false;
  }
  E& get() { return e_; }
  const E& get() const { return e_; }

 private:
  std::string name_;
  E e_;
};

}  // namespace ident
