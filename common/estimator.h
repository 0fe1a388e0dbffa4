// The one interface of ident's estimators: the recursive regression estimators (RLS, the Kárný–Hangos
// Cauchy/Student-t family, the log-concave Gaussian filter run on θ, the batch references) and the state
// observers (Kalman, log-concave Gaussian, truncated Gaussian, grid) are all models of it.
//
// Every estimator holds a Gaussian-summarised belief about an unknown vector (the parameters θ of a
// regression, the state x(k) of a state-space model) and takes data items of one kind:
//
//   RegressionItem  d(t) = (y(t), z(t)): y(t) = z(t)'θ + e(t)                 (AnyRegressionEstimator)
//   StateSpaceItem  d(k) = (u(k−1), y(k)): x(k) = A x(k−1) + B u(k−1) + v,     (AnyStateObserver)
//                   y(k) read through a measurement of x(k)
//
//   StepReport Update(item)   one step; an item of the other kind is refused (kRejectedInvalid, state unchanged)
//   mean(), covariance()      the estimate (θ̂ or x̂(k)) and its covariance
//   double Predict(item)      the one-step prediction of the item's reading before it is used: z'θ̂ for a
//                             regression; c'(A x̂ + B u) for an observer whose measurement depends on x
//                             through c'x (NaN otherwise) — for linear-Gaussian readings E[y(k) | data to k−1]
//   Reset()                   back to the prior the estimator was built with
//
// The concrete estimators keep their own, faster entry points (Update(y, z), the observers' Predict/Correct);
// MakeEstimator (ident/registry/estimator_registry.h) builds any of them by name behind AnyEstimator.
//
// Example:
//   auto est = ident::MakeEstimator(ident::ParseEstimatorSpec("cauchy"), ident::RegressionProblem{4});
//   for (...) est->Update(ident::RegressionItem{y, z});
//   Eigen::VectorXd theta = est->mean();
#pragma once

#include <concepts>
#include <limits>
#include <string>
#include <string_view>

#include <Eigen/Core>

#include "common/step_report.h"

namespace ident {

// d(t) = (y(t), z(t)) of a regression y(t) = z(t)'θ + e(t). Refers to z; no copy.
struct RegressionItem {
  double y = 0.0;
  Eigen::Ref<const Eigen::VectorXd> z;
};

// d(k) = (u(k−1), y(k)) of a state-space model: the input applied over the last sampling interval and
// the reading taken at its end.
struct StateSpaceItem {
  Eigen::VectorXd u;  // u(k−1), size = number of inputs (may be empty)
  double y = 0.0;     // y(k)
};

enum class ItemKind { kRegression, kStateSpace };

constexpr std::string_view ToString(ItemKind kind) {
  return kind == ItemKind::kRegression ? "regression" : "state-space";
}

// The compile-time form: E is an estimator for items of type Item.
template <class E, class Item>
concept Estimator = requires(E& e, const E& ce, const Item& d) {
  { e.Update(d) } -> std::same_as<StepReport>;
  { ce.mean() } -> std::convertible_to<Eigen::VectorXd>;
  { ce.covariance() } -> std::convertible_to<Eigen::MatrixXd>;
  { ce.Predict(d) } -> std::convertible_to<double>;
  {e.Reset()};
};

// The run-time form: every registered estimator, whatever the kind of its items.
class AnyEstimator {
 public:
  virtual ~AnyEstimator() = default;
  virtual std::string name() const = 0;
  // The kind of item Update takes.
  virtual ItemKind item_kind() const = 0;
  // Size of mean(): ρ for a regression, n for an observer.
  virtual int dimension() const = 0;
  // One step on an item of the estimator's kind; an item of the other kind returns kRejectedInvalid and
  // leaves the state unchanged. Never throws.
  virtual StepReport Update(const RegressionItem& item) { return Refused(item); }
  virtual StepReport Update(const StateSpaceItem& item) { return Refused(item); }
  virtual Eigen::VectorXd mean() const = 0;
  virtual Eigen::MatrixXd covariance() const = 0;
  // The prediction of the item's reading from the data before it (see the header comment); NaN for an item
  // of the other kind.
  virtual double Predict(const RegressionItem&) const { return std::numeric_limits<double>::quiet_NaN(); }
  virtual double Predict(const StateSpaceItem&) const { return std::numeric_limits<double>::quiet_NaN(); }
  virtual void Reset() = 0;

 private:
  template <class Item>
  static StepReport Refused(const Item&) {
    StepReport report;
    report.status = StepStatus::kRejectedInvalid;
    return report;
  }
};

}  // namespace ident
