// ident smooth --model MODEL.json DATA.csv [--json]
// MAP smoothing with convex penalties and the dual control problem (ident/smoothing/map_smoother.h): prints the
// primal and dual objective values, the duality gap, the states x (one row per time) and the
// interior-point iteration count. The model format is described in ident/workflow/smoothing_model.h.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <ctime>
#include <functional>
#include <iostream>
#include <memory>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <nlohmann/json.hpp>

#include "cli/commands.h"
#include "cli/csv_options.h"
#include "cli/progress.h"
#include "common/error.h"
#include "ident/smoothing/map_smoother.h"
#include "ident/workflow/smoothing_model.h"

namespace ident::cli {
namespace {

struct SmoothOptions {
  std::string model;
  std::string data;
  io::CsvOptions csv;
  bool json = false;
};

std::vector<std::vector<double>> Rows(const Eigen::MatrixXd& m) {  // one row per time (column of m)
  std::vector<std::vector<double>> rows(m.cols());
  for (int t = 0; t < m.cols(); ++t) rows[t].assign(m.col(t).data(), m.col(t).data() + m.rows());
  return rows;
}

void RunSmooth(const SmoothOptions& o) {
  const MapSmootherProblem p = workflow::ReadSmoothProblem(o.model, o.data, o.csv);
  Progress progress("smooth");
  MapSmootherOptions options;
  // The interior-point method's relative KKT residual falls about geometrically (superlinearly near the end).
  options.on_iteration = DecadesProgress(progress, options.tolerance, "decades of the KKT residual down to the tolerance");
  const auto start = std::chrono::steady_clock::now();
  const std::clock_t cpu_start = std::clock();
  const MapSmootherResult r = SolveMapSmoother(p, options);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const double cpu_seconds = static_cast<double>(std::clock() - cpu_start) / CLOCKS_PER_SEC;
  if (r.status != MapSmootherStatus::kConverged)
    throw DataError(fmt::format("{} with {}: {}", o.data, o.model, r.message));
  if (o.json) {
    nlohmann::ordered_json j;
    j["primal"] = r.primal;
    j["dual"] = r.dual;
    j["gap"] = r.gap;
    j["relative_gap"] = r.relative_gap;
    j["iterations"] = r.iterations;
    j["x"] = Rows(r.x);
    j["u"] = Rows(r.u);
    j["y"] = Rows(r.y);
    j["max_abs_x_from_dual_difference"] = r.max_abs_x_difference;
    j["reconstruction_unique"] = r.reconstruction_unique;
    j["nonunique_reconstruction_steps"] = r.nonunique_steps;  // t where d f_t*(y_t) is not a single point
    j["dual_infeasibility"] = r.dual_infeasibility;
    j["solve_seconds"] = seconds;  // SolveMapSmoother alone (no file I/O), for benchmark scripts
    j["solve_cpu_seconds"] = cpu_seconds;
    // The duality certificate (ident/smoothing/map_smoother.h): primal - optimum <= gap + gap_error_bound.
    j["status"] = ToString(r.status);
    j["kkt_residual"] = r.kkt_residual;
    j["gap_error_bound"] = r.gap_error_bound;
    j["relative_gap_bound"] = std::isfinite(r.relative_gap_bound) ? nlohmann::ordered_json(r.relative_gap_bound)
                                                                  : nlohmann::ordered_json(nullptr);
    std::cout << j.dump(2) << "\n";
    return;
  }
  fmt::print("{}: MAP smoothing of {} time steps (n = {}, nz = {}) with {}\n", o.data, p.T() + 1, p.state_dim(),
             p.measurement_dim(), o.model);
  fmt::print("interior point: {}\n", r.message);
  fmt::print("primal (P) {:.12g}\ndual   (D) {:.12g}\ngap        {:.3e} (relative {:.3e})\n", r.primal, r.dual, r.gap,
             r.relative_gap);
  fmt::print("certified  primal - optimum <= {:.3e} (relative {:.3e}; round-off bound of the gap {:.1e})\n",
             r.gap + r.gap_error_bound, r.relative_gap_bound, r.gap_error_bound);
  fmt::print("max |x - x from dual| {:.3e}\n", r.max_abs_x_difference);
  if (!r.reconstruction_unique) {
    const size_t shown = std::min<size_t>(r.nonunique_steps.size(), 20);
    fmt::print("w_t in d f_t*(y_t) is not unique at {} of {} steps (f_t* has a kink at y_t): t = {}{}\n",
               r.nonunique_steps.size(), p.T() + 1,
               fmt::join(r.nonunique_steps.begin(), r.nonunique_steps.begin() + shown, ", "),
               shown < r.nonunique_steps.size() ? ", ..." : "");
  }
  fmt::print("\n  {:>6}", "t");
  for (int i = 0; i < p.state_dim(); ++i) fmt::print(" {:>14}", fmt::format("x{}", i + 1));
  fmt::print("\n");
  for (int t = 0; t <= p.T(); ++t) {
    fmt::print("  {:>6}", t);
    for (int i = 0; i < p.state_dim(); ++i) fmt::print(" {:>14.8g}", r.x(i, t));
    fmt::print("\n");
  }
}

}  // namespace

void AddSmoothCommand(CLI::App& app) {
  auto o = std::make_shared<SmoothOptions>();
  CLI::App* cmd =
      app.add_subcommand("smooth", "MAP state smoothing with convex penalties, and its dual control problem");
  cmd->add_option("--model", o->model, "JSON model: F, H, initial, process, measurement (docs/reference/cli.md)")
      ->required();
  cmd->add_option("DATA", o->data, "CSV with measurement column z (or z1, z2, ...), one row per time")->required();
  cmd->add_flag("--json", o->json, "Print one JSON object {primal, dual, gap, x, iterations, ...}");
  AddDelimiterOption(*cmd, o->csv);
  cmd->callback([o] { RunSmooth(*o); });
}

}  // namespace ident::cli
