// An AnyRegressionEstimator that forwards every call to another one: a base for test decorators that
// watch how the workflow drives an estimator (override the calls to observe, then call the base).
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <utility>

#include "ident/regression/regression_estimator.h"

namespace ident::testing {

class ForwardingEstimator : public AnyRegressionEstimator {
 public:
  explicit ForwardingEstimator(std::unique_ptr<AnyRegressionEstimator> inner) : inner_(std::move(inner)) {}
  std::string name() const override { return inner_->name(); }
  StepReport Update(double y, const Eigen::Ref<const Eigen::VectorXd>& z) override { return inner_->Update(y, z); }
  int num_parameters() const override { return inner_->num_parameters(); }
  Eigen::VectorXd parameters() const override { return inner_->parameters(); }
  Eigen::MatrixXd covariance() const override { return inner_->covariance(); }
  double Predict(const Eigen::Ref<const Eigen::VectorXd>& z) const override { return inner_->Predict(z); }
  double nu() const override { return inner_->nu(); }
  double Dy() const override { return inner_->Dy(); }
  double noise_std() const override { return inner_->noise_std(); }
  void Reset() override { inner_->Reset(); }
  std::optional<LockInStatus> lock_in() const override { return inner_->lock_in(); }
  long restarts() const override { return inner_->restarts(); }
  bool judges_outliers() const override { return inner_->judges_outliers(); }
  bool in_startup() const override { return inner_->in_startup(); }
  std::string kind() const override { return inner_->kind(); }
  bool BeginPass() override { return inner_->BeginPass(); }
  bool FinishStartup() override { return inner_->FinishStartup(); }
  bool ReconsiderAtEnd() override { return inner_->ReconsiderAtEnd(); }

 private:
  std::unique_ptr<AnyRegressionEstimator> inner_;
};

}  // namespace ident::testing
