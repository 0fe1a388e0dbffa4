// The common interface of ident's state observers (Kalman filter, log-concave Gaussian filter,
// truncated-Gaussian assumed-density filter, grid Bayesian observer, covariance bound tracker).
//
// A state-space data item is d(k) = (u(k−1), y(k)): the input applied over the last sampling interval
// and the reading taken at its end. Update(d) runs the time update with u(k−1) (dynamics and process
// noise, [1, eqs. (1)-(2)]) and then the measurement update with y(k) [1, eq. (3)].
//
//   StepReport E::Update(const StateSpaceItem&)   one step; StepStatus says whether the state changed
//   mean()                                         state estimate x̂(k) (posterior mean)
//   covariance()                                   its covariance (for the bound tracker: the bound)
//
// Run time: AnyStateObserver is the observers' side of the one estimator interface (common/estimator.h);
// StateObserverModel wraps any such E, and the registry (ident/registry/estimator_registry.h) builds "kalman",
// "lc_gaussian", "lc_truncated" or "grid" by name.
//
// Example:
//   ident::KalmanFilter kf(model, measurement, x0, P0);
//   for (const auto& d : items) kf.Update(d);
//
// [1] T. Henningsson, K. J. Åström, "Log-concave Observers", MTNS 2006.
#pragma once

#include <concepts>
#include <limits>
#include <string>
#include <utility>

#include <Eigen/Core>

#include "common/estimator.h"
#include "common/step_report.h"
#include "models/state_space.h"

namespace ident {

template <class E>
concept StateObserver = requires(E& e, const E& ce, const StateSpaceItem& d) {
  { e.Update(d) } -> std::same_as<StepReport>;
  { ce.mean() } -> std::convertible_to<Eigen::VectorXd>;
  { ce.covariance() } -> std::convertible_to<Eigen::MatrixXd>;
};

// The observers' side of the one estimator interface: items (u(k−1), y(k)).
class AnyStateObserver : public AnyEstimator {
 public:
  using AnyEstimator::Predict;
  using AnyEstimator::Update;
  ItemKind item_kind() const final { return ItemKind::kStateSpace; }
  int dimension() const final { return num_states(); }
  StepReport Update(const StateSpaceItem& item) override = 0;
  virtual int num_states() const = 0;
};

// Adapter: wraps a concrete observer E built for `model`. Predict(d) is c'(A x̂ + B u(k−1)) — the mean of
// c'x(k) after the time update, exact for every observer, since the dynamics are linear with zero-mean
// noise — for a measurement that depends on x through c'x (`c` given), NaN otherwise. Reset() restores the
// observer as it was built.
template <StateObserver E>
class StateObserverModel final : public AnyStateObserver {
 public:
  template <class... Args>
  StateObserverModel(std::string name, models::LinearStateSpace model, Eigen::VectorXd c, Args&&... args)
      : name_(std::move(name)),
        model_(std::move(model)),
        c_(std::move(c)),
        e_(std::forward<Args>(args)...),
        initial_(e_) {}
  std::string name() const override { return name_; }
  StepReport Update(const StateSpaceItem& item) override { return e_.Update(item); }
  int num_states() const override { return static_cast<int>(e_.mean().size()); }
  Eigen::VectorXd mean() const override { return e_.mean(); }
  Eigen::MatrixXd covariance() const override { return e_.covariance(); }
  double Predict(const StateSpaceItem& item) const override {
    const Eigen::VectorXd x = e_.mean();
    if (c_.size() != x.size() || !model_.FitsStep(x.size(), item.u)) return std::numeric_limits<double>::quiet_NaN();
    double s = c_.dot(model_.A * x);
    if (model_.num_inputs() > 0) s += c_.dot(model_.B * item.u);
    return s;
  }
  void Reset() override { e_ = initial_; }
  E& get() { return e_; }
  const E& get() const { return e_; }

 private:
  std::string name_;
  models::LinearStateSpace model_;
  Eigen::VectorXd c_;
  E e_;
  E initial_;
};

}  // namespace ident
