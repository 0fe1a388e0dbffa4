// The state observers of the registry (estimator_registry.h): their problem and their typed builder.
//
//   "kalman"       KalmanFilter (square-root); needs a linear-Gaussian measurement; no options
//   "lc_gaussian"  LcGaussianFilter (exact tilted moments, the assumed-density filter); needs a
//                  measurement that depends on x through c'x (models::ProjectedMeasurement); no options
//   "lc_truncated" TruncatedGaussianFilter (the assumed-density filter on Gaussians restricted to the
//                  current reading's interval); needs a models::ThresholdSensor on 2 states; no options
//   "grid"         GridObserver (1 to 3 states); options points (one count for every axis, or per axis
//                  as 64x48), initial_sigmas, noise_sigmas, support_level, min_half_width, padding
//
// Specs and options are those of every estimator (estimator_settings.h), e.g. "grid:points=64,noise_sigmas=5".
// Every option is checked: an unknown option, a value that is not a number or out of range, a regression
// setting (dof, forgetting, …), or a measurement the observer cannot use throws InvalidArgument naming the
// observer and the option.
//
// Example:
//   ident::ObserverProblem problem{model, std::make_shared<ident::models::ThresholdSensor>(c, 1.0), x0, P0};
//   auto obs = ident::MakeStateObserver(ident::ParseEstimatorSpec("grid:points=64"), problem);
//   for (const auto& d : items) obs->Update(d);     // d = (u(k−1), y(k))
//   Eigen::VectorXd m = obs->mean();
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "ident/observers/state_observer.h"
#include "ident/registry/estimator_settings.h"
#include "models/measurement.h"
#include "models/state_space.h"

namespace ident {

// What every observer needs: the model, the measurement function and the Gaussian prior N(x0, P0).
struct ObserverProblem {
  models::LinearStateSpace model;
  std::shared_ptr<const models::MeasurementFunction> measurement;
  Eigen::VectorXd x0;
  Eigen::MatrixXd P0;
};

// Builds the observer; throws InvalidArgument naming the observer and option for an unknown name,
// an unknown or bad option, or a problem (sizes, prior, measurement) the observer cannot handle.
std::unique_ptr<AnyStateObserver> MakeStateObserver(const EstimatorSettings& settings, const ObserverProblem& problem);

// The registered observers' names, in the order they are documented.
std::vector<std::string> StateObserverNames();

}  // namespace ident
