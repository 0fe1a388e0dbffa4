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
#include <ostream>
#include <string>
#include <utility>
#include <vector>

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

// `"key": [[m(0,0), m(1,0), ...], ...]` (one inner array per time, a column of m) as nlohmann's dump(2)
// prints it at the top level of an object, written number by number: at T = 10^6 a JSON document built in
// memory would take several times the smoother's own memory.
void WriteJsonRows(std::ostream& out, const char* key, const Eigen::MatrixXd& m) {
  out << "  \"" << key << "\": [";
  for (Eigen::Index t = 0; t < m.cols(); ++t) {
    out << (t ? ",\n    [" : "\n    [");
    for (Eigen::Index i = 0; i < m.rows(); ++i) out << (i ? ",\n      " : "\n      ") << nlohmann::json(m(i, t)).dump();
    out << (m.rows() ? "\n    ]" : "]");
  }
  out << (m.cols() ? "\n  ]" : "]");
}

// The object's members in order, as nlohmann's dump(2) prints them; the members named in `rows` (null
// placeholders in j) are written by WriteJsonRows from the matching matrix.
void WriteJsonObject(std::ostream& out, const nlohmann::ordered_json& j,
                     const std::vector<std::pair<const char*, const Eigen::MatrixXd*>>& rows) {
  out << "{";
  bool first = true;
  for (const auto& item : j.items()) {
    const std::string& key = item.key();
    const nlohmann::ordered_json& value = item.value();
    out << (first ? "\n" : ",\n");
    first = false;
    const auto row = std::find_if(rows.begin(), rows.end(), [&](const auto& r) { return key == r.first; });
    if (row != rows.end()) {
      WriteJsonRows(out, row->first, *row->second);
      continue;
    }
    // A member's own dump(2), indented one level: its continuation lines gain two spaces.
    std::string text = value.dump(2);
    for (std::size_t at = text.find('\n'); at != std::string::npos; at = text.find('\n', at + 3))
      text.insert(at + 1, "  ");
    out << "  " << nlohmann::json(key).dump() << ": " << text;
  }
  out << (first ? "}" : "\n}");
}

void RunSmooth(const SmoothOptions& o) {
  const MapSmootherProblem p = workflow::ReadSmoothProblem(o.model, o.data, o.csv);
  Progress progress("smooth");
  MapSmootherOptions options;
  // The interior-point method's relative KKT residual falls about geometrically (superlinearly near the end).
  options.on_iteration =
      DecadesProgress(progress, options.tolerance, "decades of the KKT residual down to the tolerance");
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
    j["x"] = nullptr;  // written row by row (WriteJsonObject)
    j["u"] = nullptr;
    j["y"] = nullptr;
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
    WriteJsonObject(std::cout, j, {{"x", &r.x}, {"u", &r.u}, {"y", &r.y}});
    std::cout << "\n";
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
