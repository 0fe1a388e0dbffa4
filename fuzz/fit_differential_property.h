// Differential properties of `ident fit`'s computation (workflow::Fit, workflow::FitCsvFile, with the command's
// default priors) on a small ARX record built from the fuzzer's bytes, for every registered estimator:
//   - streamed vs in memory: FitCsvFile on the CSV file and Fit on the table read from it end alike —
//     both with the same error message, or both with bit-for-bit the same θ, updates and fit %;
//   - units: the record with u and y multiplied by 2^k (|k| ≤ 40; exact in binary floating point) gives
//     the same outcome — the same θ to 1e-7 relative (ARX parameters do not change when u and y are
//     scaled alike) and the fit % to 1e-6 — or, if the unscaled record is refused, an error as well.
// Input bytes: estimator, na, nb, nk, split, k, number of rows, then per row two cells (u, y), each a
// smooth signal plus a byte-chosen perturbation (an outlier of ±100 one time in 32).
#pragma once

#include <unistd.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <fstream>
#include <string>

#include <fmt/format.h>

#include "common/error.h"
#include "fuzz/fuzz_util.h"
#include "ident/io/csv.h"
#include "ident/registry/estimator_registry.h"
#include "ident/regression/regression_prior.h"
#include "ident/workflow/data_source.h"
#include "ident/workflow/fit.h"
#include "models/arx.h"

namespace ident::fuzz {

namespace fit_differential_internal {

struct Outcome {
  bool ok = false;
  std::string error;
  workflow::FitResult result;
};

inline Outcome Run(const std::string& path, bool streamed, const EstimatorSettings& settings,
                   const models::ArxStructure& arx, const workflow::FitOptions& options) {
  Outcome o;
  try {
    // The default priors of `ident fit` (cli/fit_command.cc): in the data's own scale — RLS the flat
    // prior of the estimation part's mean squares, the others their scale-invariant start-up prior —
    // without the absolute small-information check.
    workflow::FitOptions fit = options;
    fit.min_regressor_information = 0;
    EstimatorSettings chosen = settings;
    auto source = workflow::MakeArxSource(io::CsvReader(path).names(), "y", {"u"}, arx, path);
    if (chosen.name == "rls") {
      Eigen::VectorXd mean_squares;
      if (streamed) {
        mean_squares = workflow::CsvEstimationMeanSquares(path, {}, *source, fit);
      } else {
        io::DataTable table = io::ReadCsv(path);
        mean_squares =
            workflow::EstimationMeanSquares(table, workflow::PrepareData(table, *source, fit).first, *source);
      }
      if ((mean_squares.array() >= 1e-280).all() && (mean_squares.array() <= 1e280).all())
        chosen.prior = RegressionPrior::Flat(mean_squares);
      else
        fit.min_regressor_information = options.min_regressor_information;
    }
    auto estimator = MakeRegressionEstimator(chosen, source->num_parameters());
    o.result = streamed ? workflow::FitCsvFile(path, {}, *source, *estimator, fit)
                        : workflow::Fit(io::ReadCsv(path), *source, *estimator, fit);
    o.ok = true;
  } catch (const InvalidArgument& e) {
    o.error = e.what();
  } catch (const DataError& e) {
    o.error = e.what();
  }
  return o;
}

inline std::string Path(const char* name) {
  static const ScratchDir dir("ident-fit-fuzz-");
  return dir.path() + "/" + name;
}

}  // namespace fit_differential_internal

inline std::string FitDifferentialProperty(const std::uint8_t* data, std::size_t size) {
  using namespace fit_differential_internal;
  ByteReader in(data, size);
  static const char* const kEstimators[] = {"rls", "cauchy", "student:3", "huber", "cauchy-ml"};
  const std::string name = kEstimators[in.Byte() % 5];
  const int na = in.Byte() % 3, nb = 1 + in.Byte() % 2, nk = in.Byte() % 3;
  workflow::FitOptions options;
  options.split = in.Byte() % 2 ? 1.0 : 0.5;
  const int k = static_cast<int>(in.Byte() % 81) - 40;
  const int rows = 12 + in.Byte() % 90;
  std::string text = "u,y\n", scaled = "u,y\n";
  double y1 = 0, y2 = 0, u1 = 0;
  for (int r = 0; r < rows; ++r) {
    const std::uint8_t a = in.Byte(), b = in.Byte();
    const double u = std::sin(0.37 * r) + (static_cast<int>(a) - 128) / 256.0;
    double e = (static_cast<int>(b) - 128) / 1024.0;
    if (b % 32 == 0) e += (b & 32 ? 100.0 : -100.0);
    const double y = 1.2 * y1 - 0.4 * y2 + 0.5 * u1 + e;
    y2 = y1, y1 = y, u1 = u;
    text += fmt::format("{:.17g},{:.17g}\n", u, y);
    scaled += fmt::format("{:.17g},{:.17g}\n", std::ldexp(u, k), std::ldexp(y, k));
  }
  const std::string path = Path("d.csv"), scaled_path = Path("s.csv");
  std::ofstream(path, std::ios::trunc) << text;
  std::ofstream(scaled_path, std::ios::trunc) << scaled;

  models::ArxStructure arx(na, {nb}, {nk});
  const EstimatorSettings settings = ParseEstimatorSpec(name);
  const Outcome memory = Run(path, false, settings, arx, options);
  const Outcome streamed = Run(path, true, settings, arx, options);
  const std::string what = fmt::format("{} ARX({},{},{}) split {} rows {}", name, na, nb, nk, options.split, rows);
  if (memory.ok != streamed.ok)
    return fmt::format("streamed and in-memory differ ({}): '{}' vs '{}'", what, memory.error, streamed.error);
  if (!memory.ok) {
    if (memory.error != streamed.error)
      return fmt::format("streamed and in-memory errors differ ({}): '{}' vs '{}'", what, memory.error, streamed.error);
  } else {
    const workflow::FitResult &a = memory.result, &b = streamed.result;
    if (a.theta != b.theta || a.updates != b.updates ||
        !(a.validation.one_step == b.validation.one_step ||
          (std::isnan(a.validation.one_step) && std::isnan(b.validation.one_step))))
      return fmt::format("streamed and in-memory results differ ({})", what);
  }
  const Outcome in_units = Run(scaled_path, false, settings, arx, options);
  if (!memory.ok) {
    if (in_units.ok) return fmt::format("refused, but accepted × 2^{} ({}): '{}'", k, what, memory.error);
    return "";
  }
  if (!in_units.ok) return fmt::format("accepted, but refused × 2^{} ({}): '{}'", k, what, in_units.error);
  const workflow::FitResult &a = memory.result, &s = in_units.result;
  for (int i = 0; i < a.theta.size(); ++i)
    if (!(std::abs(s.theta(i) - a.theta(i)) <= 1e-7 * (1 + std::abs(a.theta(i)))))
      return fmt::format("theta {} differs × 2^{} ({}): {} vs {}", i, k, what, s.theta(i), a.theta(i));
  if (!(std::abs(s.validation.one_step - a.validation.one_step) <= 1e-6))
    return fmt::format("fit % differs × 2^{} ({}): {} vs {}", k, what, s.validation.one_step, a.validation.one_step);
  return "";
}

}  // namespace ident::fuzz
