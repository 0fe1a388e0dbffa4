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
// Run time: AnyStateObserver wraps any such E behind a virtual interface; MakeStateObserver() in
// ident/observers/observer_registry.h builds "kalman", "lc_gaussian", "lc_truncated" or "grid" by name.
//
// Example:
//   ident::KalmanFilter kf(model, measurement, x0, P0);
//   for (const auto& d : items) kf.Update(d);
//
// [1] T. Henningsson, K. J. Åström, "Log-concave Observers", MTNS 2006.
#pragma once

#include <concepts>
#include <string>
#include <utility>

#include <Eigen/Core>

#include "common/step_report.h"

namespace ident {

struct StateSpaceItem {
  Eigen::VectorXd u;  // u(k−1), size = number of inputs (may be empty)
  double y = 0.0;     // y(k)
};

template <class E>
concept StateObserver = requires(E& e, const E& ce, const StateSpaceItem& d) {
  { e.Update(d) } -> std::same_as<StepReport>;
  { ce.mean() } -> std::convertible_to<Eigen::VectorXd>;
  { ce.covariance() } -> std::convertible_to<Eigen::MatrixXd>;
};

// Type-erased state observer for selection at run time.
class AnyStateObserver {
 public:
  virtual ~AnyStateObserver() = default;
  virtual std::string name() const = 0;
  virtual StepReport Update(const StateSpaceItem& item) = 0;
  virtual int num_states() const = 0;
  virtual Eigen::VectorXd mean() const = 0;
  virtual Eigen::MatrixXd covariance() const = 0;
};

// Adapter: wraps a concrete observer E.
template <StateObserver E>
class StateObserverModel final : public AnyStateObserver {
 public:
  template <class... Args>
  explicit StateObserverModel(std::string name, Args&&... args)
      : name_(std::move(name)), e_(std::forward<Args>(args)...) {}
  std::string name() const override { return name_; }
  StepReport Update(const StateSpaceItem& item) override { return e_.Update(item); }
  int num_states() const override { return static_cast<int>(e_.mean().size()); }
  Eigen::VectorXd mean() const override { return e_.mean(); }
  Eigen::MatrixXd covariance() const override { return e_.covariance(); }
  E& get() { return e_; }
  const E& get() const { return e_; }

 private:
  std::string name_;
  E e_;
};

}  // namespace ident
