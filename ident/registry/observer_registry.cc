#include "ident/registry/observer_registry.h"

#include <cmath>
#include <functional>
#include <utility>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "common/error.h"
#include "ident/observers/grid_observer.h"
#include "ident/observers/kalman_filter.h"
#include "ident/observers/lc_gaussian_filter.h"
#include "ident/observers/truncated_gaussian_filter.h"

namespace ident {
namespace {

using ObserverFactory =
    std::function<std::unique_ptr<AnyStateObserver>(const EstimatorSettings&, const ObserverProblem&)>;

void RequireNoObserverOptions(const EstimatorSettings& s) {
  if (s.options.empty()) return;
  IDENT_REQUIRE(false, "observer '{}' takes no options; got '{}'", s.name, s.options.begin()->first);
}

std::shared_ptr<const models::ProjectedMeasurement> Projected(const EstimatorSettings& s, const ObserverProblem& p) {
  IDENT_REQUIRE(p.measurement != nullptr, "observer '{}': measurement must not be null", s.name);
  auto projected = std::dynamic_pointer_cast<const models::ProjectedMeasurement>(p.measurement);
  IDENT_REQUIRE(projected != nullptr,
                "observer '{}' needs a measurement that depends on x through c'x; '{}' does not (use grid)", s.name,
                p.measurement->name());
  return projected;
}

std::unique_ptr<AnyStateObserver> MakeKalman(const EstimatorSettings& s, const ObserverProblem& p) {
  RequireNoObserverOptions(s);
  const auto projected = Projected(s, p);
  const auto* gaussian = dynamic_cast<const models::GaussianMeasurement*>(projected.get());
  IDENT_REQUIRE(gaussian != nullptr,
                "observer 'kalman' needs a linear-Gaussian measurement; '{}' is not (use lc_gaussian or grid)",
                p.measurement->name());
  return std::make_unique<StateObserverModel<KalmanFilter>>("kalman", p.model, projected->c(), p.model, *gaussian, p.x0,
                                                            p.P0);
}

std::unique_ptr<AnyStateObserver> MakeLcGaussian(const EstimatorSettings& s, const ObserverProblem& p) {
  RequireNoObserverOptions(s);
  const auto projected = Projected(s, p);
  return std::make_unique<StateObserverModel<LcGaussianFilter>>("lc_gaussian", p.model, projected->c(), p.model,
                                                                projected, p.x0, p.P0);
}

std::unique_ptr<AnyStateObserver> MakeLcTruncated(const EstimatorSettings& s, const ObserverProblem& p) {
  RequireNoObserverOptions(s);
  IDENT_REQUIRE(p.measurement != nullptr, "observer 'lc_truncated': measurement must not be null");
  const auto* threshold = dynamic_cast<const models::ThresholdSensor*>(p.measurement.get());
  IDENT_REQUIRE(threshold != nullptr && threshold->num_states() == 2,
                "observer 'lc_truncated' needs a threshold sensor on 2 states; '{}' is not (use lc_gaussian or grid)",
                p.measurement->name());
  IDENT_REQUIRE(p.x0.size() == 2 && p.P0.rows() == 2 && p.P0.cols() == 2,
                "observer 'lc_truncated': x0 has {} entries and P0 is {}×{}; need 2 and 2×2", p.x0.size(), p.P0.rows(),
                p.P0.cols());
  return std::make_unique<StateObserverModel<TruncatedGaussianFilter>>(
      "lc_truncated", p.model, threshold->c(), p.model, *threshold, Eigen::Vector2d(p.x0), Eigen::Matrix2d(p.P0));
}

std::unique_ptr<AnyStateObserver> MakeGrid(const EstimatorSettings& s, const ObserverProblem& p) {
  IDENT_REQUIRE(p.measurement != nullptr, "observer 'grid': measurement must not be null");
  const int n = static_cast<int>(p.x0.size());
  IDENT_REQUIRE(n >= 1 && n <= 3, "observer 'grid' handles 1 to 3 states; the problem has {}", n);
  GridObserverOptions o;
  o.points.assign(n, o.points.front());
  for (const auto& [key, value] : s.options) {
    if (key == "points") {
      std::vector<int> points;
      std::string_view rest = value;
      while (true) {
        const auto x = rest.find('x');
        points.push_back(ParseOptionInteger("grid", key, rest.substr(0, x)));
        if (x == std::string_view::npos) break;
        rest.remove_prefix(x + 1);
      }
      IDENT_REQUIRE(points.size() == 1 || static_cast<int>(points.size()) == n,
                    "observer 'grid': option points = '{}' has {} counts; need 1 or {} (one per state)", value,
                    points.size(), n);
      o.points = points.size() == 1 ? std::vector<int>(n, points.front()) : points;
    } else if (key == "initial_sigmas") {
      o.initial_sigmas = ParseOptionNumber("grid", key, value);
    } else if (key == "noise_sigmas") {
      o.noise_sigmas = ParseOptionNumber("grid", key, value);
    } else if (key == "support_level") {
      o.support_level = ParseOptionNumber("grid", key, value);
    } else if (key == "min_half_width") {
      o.min_half_width = ParseOptionNumber("grid", key, value);
    } else if (key == "padding") {
      o.padding = ParseOptionInteger("grid", key, value);
    } else {
      IDENT_REQUIRE(false,
                    "observer 'grid' has no option '{}' (options: points, initial_sigmas, noise_sigmas, "
                    "support_level, min_half_width, padding)",
                    key);
    }
  }
  const std::string problem = o.Validate();
  IDENT_REQUIRE(problem.empty(), "observer 'grid': option {}", problem);
  const auto* projected = dynamic_cast<const models::ProjectedMeasurement*>(p.measurement.get());
  return std::make_unique<StateObserverModel<GridObserver>>("grid", p.model,
                                                            projected != nullptr ? projected->c() : Eigen::VectorXd(),
                                                            p.model, p.measurement, p.x0, p.P0, o);
}

const std::vector<std::pair<std::string, ObserverFactory>>& ObserverEntries() {
  static const std::vector<std::pair<std::string, ObserverFactory>> registry = {
      {"kalman", MakeKalman},
      {"lc_gaussian", MakeLcGaussian},
      {"lc_truncated", MakeLcTruncated},
      {"grid", MakeGrid},
  };
  return registry;
}

}  // namespace

std::unique_ptr<AnyStateObserver> MakeStateObserver(const EstimatorSettings& settings, const ObserverProblem& problem) {
  const std::string setting = settings.first_regression_setting();
  IDENT_REQUIRE(setting.empty(), "{} does not apply to observer '{}' (a regression estimator's setting)", setting,
                settings.name);
  for (const auto& [name, factory] : ObserverEntries()) {
    if (name == settings.name) return factory(settings, problem);
  }
  IDENT_REQUIRE(false, "unknown observer '{}' (known: {})", settings.name, fmt::join(StateObserverNames(), ", "));
  return nullptr;  // unreachable
}

std::vector<std::string> StateObserverNames() {
  std::vector<std::string> names;
  for (const auto& [name, factory] : ObserverEntries()) names.push_back(name);
  return names;
}

}  // namespace ident
