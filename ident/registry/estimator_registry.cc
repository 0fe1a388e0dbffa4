#include "ident/registry/estimator_registry.h"

#include <cmath>
#include <functional>
#include <map>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "common/error.h"
#include "ident/observers/lc_regression.h"
#include "ident/regression/batch_regression.h"
#include "ident/regression/rls.h"
#include "ident/regression/safe_student_regression.h"

namespace ident {
namespace {

using Factory = RegressionEstimatorFactory;

std::unique_ptr<AnyRegressionEstimator> MakeRls(const EstimatorSettings& s, int rho) {
  IDENT_REQUIRE(!s.dof, "dof = {} does not apply to estimator 'rls'", *s.dof);
  IDENT_REQUIRE(!s.delta,
                "delta = {} does not apply to estimator 'rls' (it is a Kárný–Hangos convention: cauchy, "
                "student)",
                s.delta.value_or(1));
  IDENT_REQUIRE(!s.lock_in.any(), "the lock-in options apply to the robust estimators (cauchy, student), not to 'rls'");
  RlsOptions options;
  options.forgetting = s.forgetting;
  options.prior = s.prior;
  return std::make_unique<RegressionEstimatorModel<RecursiveLeastSquares>>("rls", rho, options);
}

// Kárný–Hangos Student-t regression with k = dof; `name` is "cauchy" (k = 1) or "student".
std::unique_ptr<AnyRegressionEstimator> MakeStudent(const EstimatorSettings& s, int rho, const std::string& name,
                                                    double dof) {
  SafeStudentOptions
      options;  // start-up prior and lock-in safeguards unless exact (docs/explanation/karny-hangos-estimator.md)
  options.base.dof = dof;
  options.base.delta = s.delta.value_or(1);
  options.base.forgetting = s.forgetting;
  options.base.prior = s.prior;
  options.base.exact = s.exact;
  options.provisional_v0 = s.provisional_v0;
  IDENT_REQUIRE(!s.exact || !s.lock_in.any(),
                "the lock-in options have no effect with exact (the paper's recursion has no lock-in safeguard)");
  if (s.lock_in.window) options.lock_in_window = *s.lock_in.window;
  if (s.lock_in.threshold) options.lock_in_threshold = *s.lock_in.threshold;
  options.restart_on_lock_in = s.lock_in.restart;
  if (s.lock_in.history) options.history_limit = *s.lock_in.history;
  return std::make_unique<RegressionEstimatorModel<SafeStudentRegression>>(name, rho, options);
}

std::unique_ptr<AnyRegressionEstimator> MakeCauchy(const EstimatorSettings& s, int rho) {
  IDENT_REQUIRE(!s.dof || *s.dof == 1,
                "dof = {} does not apply to estimator 'cauchy' (it is student with k = 1; "
                "use --estimator student --dof {})",
                s.dof.value_or(1), s.dof.value_or(1));
  return MakeStudent(s, rho, "cauchy", 1.0);
}

std::unique_ptr<AnyRegressionEstimator> MakeStudentT(const EstimatorSettings& s, int rho) {
  IDENT_REQUIRE(s.dof.has_value(), "estimator 'student' needs dof (degrees of freedom k > 0: --dof 3 or student:3)");
  IDENT_REQUIRE(std::isfinite(*s.dof) && *s.dof > 0, "dof = {}; estimator 'student' needs a finite k > 0", *s.dof);
  // nu_hard >= (k+3-delta)/k grows without bound as k -> 0: a small k leaves the first step no valid
  // weight unless nu(1) exceeds it. Name k, not the prior, when this term alone decides.
  const double k = *s.dof;
  const int delta = s.delta.value_or(1);
  const double nu0 = s.prior ? s.prior->nu0 : rho + k + delta;
  const double nu1 = s.forgetting.stabilised ? nu0 + 1 : s.forgetting.factor * nu0 + 1;
  IDENT_REQUIRE(!(std::isfinite(nu1) && nu1 > 1 && nu1 <= (k + 3 - delta) / k),
                "dof = {} is too small: nu_hard >= (k+3-delta)/k = {:.6g} exceeds the first step's nu(1) = {:.6g} "
                "(nu0 = {:.6g}, delta = {}); need k > {:.6g}",
                k, (k + 3 - delta) / k, nu1, nu0, delta, (3 - delta) / (nu1 - 1));
  return MakeStudent(s, rho, fmt::format("student:{}", *s.dof), *s.dof);
}

// The batch robust references (ident/regression/batch_regression.h): they solve on all samples, with no prior,
// forgetting or safeguard to set.
std::unique_ptr<AnyRegressionEstimator> MakeBatch(const EstimatorSettings& s, int rho, const std::string& name,
                                                  BatchMethod method) {
  IDENT_REQUIRE(!s.dof, "dof = {} does not apply to estimator '{}'", *s.dof, name);
  IDENT_REQUIRE(!s.delta, "delta = {} does not apply to estimator '{}'", s.delta.value_or(1), name);
  IDENT_REQUIRE(s.forgetting.factor == 1 && !s.forgetting.stabilised,
                "forgetting does not apply to the batch estimator '{}' (it weighs every sample of the record)", name);
  IDENT_REQUIRE(!s.prior, "a prior does not apply to the batch estimator '{}'", name);
  IDENT_REQUIRE(!s.exact, "exact does not apply to the batch estimator '{}'", name);
  IDENT_REQUIRE(!s.lock_in.any(),
                "the lock-in options apply to the robust recursive estimators (cauchy, student), "
                "not to '{}'",
                name);
  BatchRegressionOptions options;
  options.method = method;
  return std::make_unique<RegressionEstimatorModel<BatchRegressionEstimator>>(name, rho, options);
}

// The log-concave Gaussian filter as a regression estimator (ident/observers/lc_regression.h): "lc:<noise>".
std::unique_ptr<AnyRegressionEstimator> MakeLc(const EstimatorSettings& s, int rho) {
  IDENT_REQUIRE(
      !s.noise.empty(),
      "estimator 'lc' needs a noise law: lc:laplace, lc:huber[:k], lc:logistic, lc:gengauss:p or lc:gaussian");
  const std::string name = "lc:" + s.noise;
  IDENT_REQUIRE(!s.dof, "dof = {} does not apply to estimator '{}' (a Huber corner goes in the name: lc:huber:1.5)",
                s.dof.value_or(0), name);
  IDENT_REQUIRE(!s.delta, "delta = {} does not apply to estimator '{}'", s.delta.value_or(1), name);
  IDENT_REQUIRE(!s.exact, "exact does not apply to estimator '{}'", name);
  IDENT_REQUIRE(!s.lock_in.any(), "the lock-in options apply to cauchy and student, not to '{}'", name);
  IDENT_REQUIRE(!s.prior, "a prior (nu0/V0) does not apply to estimator '{}' (it starts from a robust window fit)",
                name);
  IDENT_REQUIRE(!s.forgetting.stabilised, "stabilised forgetting does not apply to estimator '{}'", name);
  LcRegressionOptions options;
  options.noise = models::LogConcaveNoise::Parse(s.noise);
  options.forgetting = s.forgetting.factor;
  return std::make_unique<RegressionEstimatorModel<LcRegression>>(name, rho, std::move(options));
}

struct Entry {
  std::string name;
  Factory factory;
  EstimatorTraits traits;
  const char* keys;  // the spec keys it takes (estimator_settings.h), for the refusal of others
};

std::vector<Entry>& Registry() {
  static std::vector<Entry> registry = {
      {"rls", MakeRls, {.data_scaled_prior = true}, "forgetting"},
      {"cauchy",
       MakeCauchy,
       {.data_scaled_prior = true, .lock_in = true, .robust = true},
       "forgetting, delta, lock_in_window, lock_in_threshold"},
      {"student",
       MakeStudentT,
       {.data_scaled_prior = true, .lock_in = true, .robust = true},
       "k, dof, forgetting, delta, lock_in_window, lock_in_threshold"},
      {"huber",
       [](const EstimatorSettings& s, int rho) { return MakeBatch(s, rho, "huber", BatchMethod::kHuber); },
       {.robust = true},
       ""},
      {"cauchy-ml",
       [](const EstimatorSettings& s, int rho) { return MakeBatch(s, rho, "cauchy-ml", BatchMethod::kCauchyMl); },
       {.robust = true},
       ""},
      {"lc", MakeLc, {.robust = true}, ""},
  };
  return registry;
}

// The regression entry `name`, or null.
const Entry* Find(std::string_view name) {
  for (const Entry& entry : Registry())
    if (entry.name == name) return &entry;
  return nullptr;
}

[[noreturn]] void UnknownEstimator(std::string_view name) {
  for (const std::string& observer : StateObserverNames())
    if (observer == name)
      throw InvalidArgument(fmt::format(
          "'{}' is a state observer: it takes a state-space problem (model, measurement, prior), not a regression",
          name));
  throw InvalidArgument(
      fmt::format("unknown estimator '{}' (known: {})", name, fmt::join(RegressionEstimatorNames(), ", ")));
}

// The regression estimators take the typed settings only (estimator_settings.h).
void RequireNoOptions(const Entry& entry, const EstimatorSettings& s) {
  if (s.options.empty()) return;
  throw InvalidArgument(fmt::format("estimator '{}' has no option '{}' ({})", s.name, s.options.begin()->first,
                                    *entry.keys ? fmt::format("options: {}", entry.keys) : "it takes no options"));
}

}  // namespace

std::unique_ptr<AnyRegressionEstimator> MakeRegressionEstimator(const EstimatorSettings& settings, int num_parameters) {
  const Entry* entry = Find(settings.name);
  if (entry == nullptr) UnknownEstimator(settings.name);
  RequireNoOptions(*entry, settings);
  return entry->factory(settings, num_parameters);
}

std::unique_ptr<AnyEstimator> MakeEstimator(const EstimatorSettings& settings, const RegressionProblem& problem) {
  return MakeRegressionEstimator(settings, problem.num_parameters);
}

std::unique_ptr<AnyEstimator> MakeEstimator(const EstimatorSettings& settings, const ObserverProblem& problem) {
  if (Find(settings.name) != nullptr)
    throw InvalidArgument(
        fmt::format("'{}' is a regression estimator: it takes a regression problem (items y, z), not a state-space one",
                    settings.name));
  return MakeStateObserver(settings, problem);
}

std::vector<std::string> EstimatorNames() {
  std::vector<std::string> names = RegressionEstimatorNames();
  for (std::string& name : StateObserverNames()) names.push_back(std::move(name));
  return names;
}

ItemKind EstimatorItemKind(std::string_view name) {
  if (Find(name) != nullptr) return ItemKind::kRegression;
  for (const std::string& observer : StateObserverNames())
    if (observer == name) return ItemKind::kStateSpace;
  UnknownEstimator(name);
}

std::vector<std::string> RegressionEstimatorNames() {
  std::vector<std::string> names;
  for (const Entry& entry : Registry()) names.push_back(entry.name);
  return names;
}

EstimatorTraits RegressionEstimatorTraits(std::string_view name) {
  const Entry* entry = Find(name);
  if (entry == nullptr) UnknownEstimator(name);
  return entry->traits;
}

void RegisterRegressionEstimator(const std::string& name, RegressionEstimatorFactory factory, EstimatorTraits traits) {
  IDENT_REQUIRE(!name.empty() && name.find_first_of(":, ") == std::string::npos,
                "estimator name '{}': need a non-empty name without ':', ',' or spaces", name);
  IDENT_REQUIRE(factory, "estimator '{}': no factory", name);
  for (const std::string& taken : EstimatorNames())
    IDENT_REQUIRE(taken != name, "estimator '{}' is registered already", name);
  Registry().push_back({name, std::move(factory), traits, ""});  // a registered estimator takes no spec keys
}

std::optional<RegressionPrior> DataScaledDefaultPrior(const EstimatorSettings& settings,
                                                      const Eigen::VectorXd& mean_squares) {
  const EstimatorTraits traits = RegressionEstimatorTraits(settings.name);
  if (!traits.data_scaled_prior || traits.lock_in || settings.prior || settings.exact) return {};
  if (!((mean_squares.array() >= 1e-280).all() && (mean_squares.array() <= 1e280).all())) return {};
  return RegressionPrior::Flat(mean_squares);
}

bool UseDataScaledPrior(EstimatorSettings& settings, const Eigen::VectorXd& mean_squares) {
  const EstimatorTraits traits = RegressionEstimatorTraits(settings.name);
  if (!traits.data_scaled_prior || settings.prior || settings.exact) return false;
  if (traits.lock_in) {
    settings.provisional_v0 = DataScaledProvisionalV0(mean_squares);
    return settings.provisional_v0.has_value();
  }
  settings.prior = DataScaledDefaultPrior(settings, mean_squares);
  return settings.prior.has_value();
}

}  // namespace ident
