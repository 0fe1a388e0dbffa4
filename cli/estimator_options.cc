#include "cli/estimator_options.h"

#include <cstdlib>
#include <filesystem>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "common/error.h"
#include "ident/io/csv.h"

#ifndef IDENT_DATASETS_DIR
#define IDENT_DATASETS_DIR "datasets"
#endif

namespace ident::cli {

void EstimatorCliOptions::AddTo(CLI::App& app, bool with_estimator) {
  if (with_estimator)
    app.add_option(
           "--estimator", estimator,
           fmt::format(
               "Estimator: {} (dof as 'student:3'; lc with a noise law: lc:laplace, lc:huber:1.345, lc:logistic, "
               "lc:gengauss:1.5, lc:gaussian)",
               fmt::join(RegressionEstimatorNames(), ", ")))
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
  app.add_option("--history-limit", history_limit,
                 "cauchy/student: samples kept for a restart to replay (0 = all, the default; else at least the "
                 "lock-in window): bounds the memory of a long stream, and a restart then replays only the last ones");
}

std::string ResolveDataPath(const std::string& name) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (name == io::kStandardInput || fs::exists(name, ec) || name.find('/') != std::string::npos) return name;
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
