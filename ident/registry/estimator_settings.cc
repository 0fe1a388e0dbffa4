#include "ident/registry/estimator_settings.h"

#include <charconv>
#include <cmath>
#include <set>

#include <fmt/format.h>

#include "common/error.h"

namespace ident {
namespace {

// The typed keys (estimator_settings.h): read into their fields, not kept in `options`.
void SetTypedKey(EstimatorSettings& s, const std::string& key, std::string_view text) {
  if (key == "k" || key == "dof") {
    s.dof = ParseOptionNumber(s.name, key, text);
  } else if (key == "forgetting") {
    s.forgetting.factor = ParseOptionNumber(s.name, key, text);
  } else if (key == "delta") {
    s.delta = ParseOptionInteger(s.name, key, text);
  } else if (key == "lock_in_window") {
    s.lock_in.window = ParseOptionInteger(s.name, key, text);
  } else if (key == "lock_in_threshold") {
    s.lock_in.threshold = ParseOptionNumber(s.name, key, text);
  } else {
    s.options[key] = std::string(text);
  }
}

}  // namespace

std::string EstimatorSettings::first_regression_setting() const {
  if (dof) return "dof";
  if (forgetting.factor != 1 || forgetting.stabilised) return "forgetting";
  if (prior) return "prior";
  if (!noise.empty()) return "noise";
  if (delta) return "delta";
  if (exact) return "exact";
  if (lock_in.any()) return "lock-in";
  return {};
}

double ParseOptionNumber(std::string_view name, std::string_view key, std::string_view text) {
  double value = 0;
  const auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  IDENT_REQUIRE(!text.empty() && ec == std::errc() && ptr == text.data() + text.size() && std::isfinite(value),
                "estimator '{}': option {} = '{}' is not a finite number", name, key, text);
  return value;
}

int ParseOptionInteger(std::string_view name, std::string_view key, std::string_view text) {
  const double value = ParseOptionNumber(name, key, text);
  IDENT_REQUIRE(value == std::floor(value) && std::abs(value) < 1e9,
                "estimator '{}': option {} = '{}' is not an integer", name, key, text);
  return static_cast<int>(value);
}

EstimatorSettings ParseEstimatorSpec(std::string_view spec, EstimatorSettings base) {
  const auto colon = spec.find(':');
  base.name = std::string(spec.substr(0, colon));
  IDENT_REQUIRE(!base.name.empty(), "estimator '{}' has no name", spec);
  if (base.name == "lc") {  // "lc:<noise>", the noise law with its own parameter ("lc:huber:1.345")
    IDENT_REQUIRE(colon != std::string_view::npos && colon + 1 < spec.size(),
                  "estimator '{}' needs a noise law: lc:laplace, lc:huber[:k], lc:logistic, lc:gengauss:p or "
                  "lc:gaussian",
                  spec);
    base.noise = std::string(spec.substr(colon + 1));
    return base;
  }
  if (colon == std::string_view::npos) return base;
  std::string_view rest = spec.substr(colon + 1);
  IDENT_REQUIRE(!rest.empty(), "estimator '{}' ends with ':'", spec);
  if (rest.find('=') == std::string_view::npos && rest.find(',') == std::string_view::npos) {
    // "name:value": the degrees of freedom ("student:3").
    double value = 0;
    const auto [ptr, ec] = std::from_chars(rest.data(), rest.data() + rest.size(), value);
    IDENT_REQUIRE(ec == std::errc() && ptr == rest.data() + rest.size(),
                  "estimator '{}': '{}' is not a number or key=value (use e.g. student:3 or grid:points=64)", spec,
                  rest);
    base.dof = value;
    return base;
  }
  std::set<std::string> seen;
  while (true) {
    const auto comma = rest.find(',');
    const std::string_view item = rest.substr(0, comma);
    const auto eq = item.find('=');
    IDENT_REQUIRE(eq != std::string_view::npos && eq > 0,
                  "estimator '{}': '{}' is not key=value (use e.g. rls:forgetting=0.99 or grid:points=64)", spec, item);
    const std::string key(item.substr(0, eq));
    IDENT_REQUIRE(seen.insert(key == "k" ? "dof" : key).second, "estimator '{}': option {} given twice", spec, key);
    SetTypedKey(base, key, item.substr(eq + 1));
    if (comma == std::string_view::npos) break;
    rest.remove_prefix(comma + 1);
    IDENT_REQUIRE(!rest.empty(), "estimator '{}' ends with ','", spec);
  }
  return base;
}

}  // namespace ident
