#include "ident/workflow/estimator_spec.h"

#include <filesystem>
#include <fstream>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "common/error.h"

namespace ident::workflow {

EstimatorSettings EstimatorSpec::Resolve(int num_parameters, const std::string& spec, long estimation_rows) const {
  const std::string& name = spec.empty() ? estimator : spec;
  EstimatorSettings s = ParseEstimatorSpec(name);
  if (dof) {
    IDENT_REQUIRE(!s.dof || *s.dof == *dof, "--dof {} contradicts estimator '{}'", *dof, name);
    s.dof = dof;
  }
  // A spec key ("rls:forgetting=0.99") and its option (--forgetting) set one field: either may give it,
  // both only with the same value.
  if (delta) {
    IDENT_REQUIRE(!s.delta || *s.delta == *delta, "--delta {} contradicts estimator '{}'", *delta, name);
    s.delta = delta;
  }
  IDENT_REQUIRE(!s.delta || *s.delta == 0 || *s.delta == 1, "delta = {}; need 0 or 1", s.delta.value_or(1));
  if (forgetting != 1) {
    IDENT_REQUIRE(s.forgetting.factor == 1 || s.forgetting.factor == forgetting,
                  "--forgetting {} contradicts estimator '{}'", forgetting, name);
    s.forgetting.factor = forgetting;
  }
  s.forgetting.stabilised = stabilised;
  s.exact = exact;
  if (lock_in_window) {
    IDENT_REQUIRE(!s.lock_in.window || *s.lock_in.window == *lock_in_window,
                  "--lock-in-window {} contradicts estimator '{}'", *lock_in_window, name);
    s.lock_in.window = lock_in_window;
  }
  if (lock_in_threshold) {
    IDENT_REQUIRE(!s.lock_in.threshold || *s.lock_in.threshold == *lock_in_threshold,
                  "--lock-in-threshold {} contradicts estimator '{}'", *lock_in_threshold, name);
    s.lock_in.threshold = lock_in_threshold;
  }
  IDENT_REQUIRE(!s.lock_in.window || estimation_rows <= 0 || *s.lock_in.window <= estimation_rows,
                "{} {} exceeds the estimation part's {} rows: the monitor could never fill; need at most {}",
                lock_in_window ? std::string("--lock-in-window") : fmt::format("estimator '{}': lock_in_window", name),
                s.lock_in.window.value_or(0), estimation_rows, estimation_rows);
  s.lock_in.restart = !no_lock_in_restart;
  s.lock_in.history = history_limit;
  if (nu0) s.prior = RegressionPrior::Diagonal(num_parameters, *nu0, *vy0, *vz0);
  IDENT_REQUIRE(!(prior && (nu0 || !prior_file.empty())),
                "give one prior: an explicit prior, nu0/vy0/vz0 or a prior file");
  IDENT_REQUIRE(!(nu0 && !prior_file.empty()), "--prior excludes --nu0/--vy0/--vz0");
  IDENT_REQUIRE(!nu0 || (vy0 && vz0), "--nu0 needs --vy0 and --vz0 (V(0) = diag(A, B·I))");
  IDENT_REQUIRE(nu0 || (!vy0 && !vz0), "--vy0 and --vz0 need --nu0");
  if (prior) s.prior = prior;
  if (!prior_file.empty()) s.prior = ReadPriorJson(prior_file, num_parameters);
  const std::string error = s.forgetting.Validate();
  IDENT_REQUIRE(error.empty(), "{}", error);
  return s;
}

RegressionPrior ReadPriorJson(const std::string& path, int num_parameters) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    throw DataError(fmt::format("cannot read '{}': it is a directory", path));
  std::ifstream in(path);
  if (!in) throw DataError(fmt::format("cannot open prior file '{}'", path));
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& e) {
    throw DataError(fmt::format("{}: not valid JSON ({})", path, e.what()));
  } catch (const std::exception& e) {  // the stream failed (e.g. a device that cannot be read)
    throw DataError(fmt::format("cannot read '{}': {}", path, e.what()));
  }
  if (!j.is_object() || !j.contains("nu0") || !j["nu0"].is_number() || !j.contains("V0") || !j["V0"].is_array())
    throw DataError(fmt::format("{}: need an object {{\"nu0\": N, \"V0\": [[...], ...]}}", path));
  for (const auto& item : j.items()) {
    if (item.key() == "nu0" || item.key() == "V0") continue;
    const std::string& key = item.key();
    const std::string shown = key.size() > 32 ? key.substr(0, 32) + "..." : key;  // JSON-escaped below
    throw DataError(fmt::format("{}: unknown key {} (known: nu0, V0)", path,
                                nlohmann::json(shown).dump(-1, ' ', true, nlohmann::json::error_handler_t::replace)));
  }
  const int n = num_parameters + 1;
  const auto& rows = j["V0"];
  if (static_cast<int>(rows.size()) != n)
    throw DataError(fmt::format("{}: V0 has {} rows; the model needs {}x{} (rho = {}, y first)", path, rows.size(), n,
                                n, num_parameters));
  RegressionPrior prior;
  prior.nu0 = j["nu0"].get<double>();
  prior.V0.resize(n, n);
  for (int i = 0; i < n; ++i) {
    if (!rows[i].is_array() || static_cast<int>(rows[i].size()) != n)
      throw DataError(fmt::format("{}: V0 row {} does not have {} numbers", path, i + 1, n));
    for (int k = 0; k < n; ++k) {
      if (!rows[i][k].is_number()) throw DataError(fmt::format("{}: V0[{}][{}] is not a number", path, i, k));
      prior.V0(i, k) = rows[i][k].get<double>();
    }
  }
  try {
    prior.Validate();
  } catch (const InvalidArgument& e) {
    throw DataError(fmt::format("{}: {}", path, e.what()));
  }
  return prior;
}

std::vector<EstimatorSettings> EstimatorSpec::ResolveAll(int num_parameters, const std::vector<std::string>& names,
                                                         long estimation_rows) const {
  std::vector<EstimatorSettings> settings;
  for (const std::string& name : names) {
    settings.push_back(Resolve(num_parameters, name, estimation_rows));
    // The lock-in options and delta are for the Kárný–Hangos estimators of the comparison (cauchy,
    // student); the others have no such safeguard or convention.
    if (!RegressionEstimatorTraits(settings.back().name).lock_in) {
      settings.back().lock_in = {};
      settings.back().delta.reset();
    }
  }
  return settings;
}

std::vector<std::string> SplitEstimatorLists(const std::vector<std::string>& lists) {
  std::vector<std::string> names;
  for (const std::string& list : lists) {
    for (std::size_t start = 0;;) {
      const std::size_t comma = list.find(',', start);
      const std::string name = list.substr(start, comma == std::string::npos ? comma : comma - start);
      IDENT_REQUIRE(!name.empty(), "--estimators: an empty estimator name in '{}'", list);
      names.push_back(name);
      if (comma == std::string::npos) break;
      start = comma + 1;
    }
  }
  return names;
}

}  // namespace ident::workflow
