#include "cli/estimator_options.h"

#include <cstdlib>
#include <filesystem>
#include <fstream>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <nlohmann/json.hpp>

#include "common/error.h"

#ifndef IDENT_DATASETS_DIR
#define IDENT_DATASETS_DIR "datasets"
#endif

namespace ident::cli {

void EstimatorCliOptions::AddTo(CLI::App& app, bool with_estimator) {
  if (with_estimator)
    app.add_option("--estimator", estimator,
                   fmt::format("Estimator: {} (dof as 'student:3')", fmt::join(RegressionEstimatorNames(), ", ")))
        ->capture_default_str();
  app.add_option("--dof", dof, "Student-t degrees of freedom k (estimator student)");
  app.add_option("--delta", delta, "cauchy/student: Kárný–Hangos ω-exponent convention δ (0 or 1; default 1)");
  auto* forgetting_option =
      app.add_option("--forgetting", forgetting, "Forgetting factor λ in (0, 1]; 1 = none")->capture_default_str();
  app.add_flag("--stabilised", stabilised, "Stabilised forgetting towards the prior instead of exponential")
      ->needs(forgetting_option);
  auto* nu0_option = app.add_option("--nu0", nu0, "Prior degrees ν(0) (with --vy0, --vz0: V(0) = diag(A, B·I))");
  auto* vy0_option = app.add_option("--vy0", vy0, "Prior V(0) output entry A");
  auto* vz0_option = app.add_option("--vz0", vz0, "Prior V(0) regressor entries B");
  nu0_option->needs(vy0_option, vz0_option);
  vy0_option->needs(nu0_option, vz0_option);
  vz0_option->needs(nu0_option, vy0_option);
  app.add_option("--prior", prior_file, "Prior as JSON {\"nu0\": N, \"V0\": [[...]]} ((ρ+1)x(ρ+1), y first)")
      ->excludes(nu0_option)
      ->excludes(vy0_option)
      ->excludes(vz0_option);
  app.add_flag("--exact", exact, "The paper's exact recursion: switch off every safeguard beyond it");
  app.add_option("--lock-in-window", lock_in_window,
                 "cauchy/student: samples M the lock-in monitor watches (0 = max(100, 20ρ))");
  app.add_option("--lock-in-threshold", lock_in_threshold,
                 "cauchy/student: a weight νβ below this counts as low; more than half of the window low = lock-in "
                 "(default 0.3)");
  app.add_flag("--no-lock-in-restart", no_lock_in_restart,
               "cauchy/student: report lock-ins but do not restart the estimator");
}

EstimatorSettings EstimatorCliOptions::Resolve(int num_parameters, const std::string& spec,
                                               long estimation_rows) const {
  const std::string& name = spec.empty() ? estimator : spec;
  EstimatorSettings s = ParseEstimatorSpec(name);
  if (dof) {
    IDENT_REQUIRE(!s.dof || *s.dof == *dof, "--dof {} contradicts estimator '{}'", *dof, name);
    s.dof = dof;
  }
  IDENT_REQUIRE(!delta || *delta == 0 || *delta == 1, "delta = {}; need 0 or 1", delta.value_or(1));
  s.delta = delta;
  s.forgetting.factor = forgetting;
  s.forgetting.stabilised = stabilised;
  s.exact = exact;
  IDENT_REQUIRE(!lock_in_window || estimation_rows <= 0 || *lock_in_window <= estimation_rows,
                "--lock-in-window {} exceeds the estimation part's {} rows: the monitor could never fill; need at "
                "most {}",
                lock_in_window.value_or(0), estimation_rows, estimation_rows);
  s.lock_in = {lock_in_window, lock_in_threshold, !no_lock_in_restart};
  if (nu0) s.prior = RegressionPrior::Diagonal(num_parameters, *nu0, *vy0, *vz0);
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

std::string ResolveDataPath(const std::string& name) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (fs::exists(name, ec) || name.find('/') != std::string::npos) return name;
  const char* env = std::getenv("IDENT_DATASETS");
  for (const std::string& dir : {std::string(env ? env : ""), std::string(IDENT_DATASETS_DIR)}) {
    if (dir.empty()) continue;
    for (const std::string& candidate : {dir + "/" + name, dir + "/" + name + ".csv"})
      if (fs::is_regular_file(candidate, ec)) return candidate;
  }
  // A bare name that is neither a file nor a dataset: say so, instead of the reader's "cannot open".
  if (name.find('.') == std::string::npos)
    throw DataError(fmt::format("no file or bundled dataset '{}' (`ident datasets` lists the bundled ones)", name));
  return name;  // the reader reports "cannot open"
}

}  // namespace ident::cli
