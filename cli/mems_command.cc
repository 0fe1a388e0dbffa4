// ident mems [--t-mean LIST] [--steps N] [--seed S] [--grid-points N] [--grid-tolerance T] [--h H]
//            [--ep-window W] [--csv FILE] [--trace FILE] [--plot FILE]
// The MEMS accelerometer study of Henningsson & Åström (2006, sec. V): prints the analogue of Fig. 9
// (RMS velocity error of each observer against the measured mean time between events) and writes the
// Fig. 8 variance traces (--trace CSV, and the second panel of --plot). See studies/mems/mems_study.h.
#include <cmath>
#include <filesystem>
#include <iostream>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "cli/commands.h"
#include "cli/gnuplot.h"
#include "cli/output_file.h"
#include "cli/output_paths.h"
#include "cli/progress.h"
#include "common/error.h"
#include "studies/mems/mems_study.h"

namespace ident::cli {
namespace {

struct MemsCommandOptions {
  std::vector<double> t_targets = {0.3, 0.5, 1.0, 1.5, 2.0, 3.0};
  int steps = 4000;
  unsigned seed = 1;
  int grid_points = 64;
  double grid_tolerance = 0.02;
  double h = 0.01;
  int ep_window = 16;
  std::string csv, trace, plot;
};

// The columns of the Fig. 9 table: (csv name, observer name in the study).
const std::vector<std::pair<std::string, std::string>> kColumns = {{"grid", "grid"},
                                                                   {"tuned_kalman", "tuned_kalman"},
                                                                   {"tuned_kalman_13", "tuned_kalman_13"},
                                                                   {"lc_gaussian", "lc_truncated"},
                                                                   {"lc_event", "lc_event"},
                                                                   {"lc_plain", "lc_plain"},
                                                                   {"lc_event_trunc", "lc_event_trunc"},
                                                                   {"lc_event_capped", "lc_event_capped"},
                                                                   {"lc_wedge", "lc_wedge"},
                                                                   {"lc_excursion", "lc_excursion"},
                                                                   {"lc_excursion_silent", "lc_excursion_silent"},
                                                                   {"lc_window", "lc_window"},
                                                                   {"lc_truncated", "lc_truncated"},
                                                                   {"bound", "bound"}};

void RunMems(const MemsCommandOptions& o) {
  IDENT_REQUIRE(!o.t_targets.empty(), "--t-mean needs at least one value");
  for (double t : o.t_targets) IDENT_REQUIRE(std::isfinite(t) && t > 0, "--t-mean value {} must be > 0", t);
  // Every option and output file is checked before the study runs, so a bad one costs no time and
  // leaves stdout empty.
  auto study_options = [&](size_t i) {
    MemsStudyOptions s;
    s.t_target = o.t_targets[i];
    s.steps = o.steps;
    s.burn_in = o.steps / 10;
    s.seed = o.seed + static_cast<unsigned>(i);
    s.grid_points = o.grid_points;
    s.grid_tolerance = o.grid_tolerance;
    s.h = o.h;
    s.ep_window = o.ep_window;
    s.record_trace = i == 0 && (!o.trace.empty() || !o.plot.empty());
    const std::string problem = s.Validate();
    IDENT_REQUIRE(problem.empty(), "{} (from --t-mean/--steps/--grid-points/--grid-tolerance/--h/--ep-window)",
                  problem);
    return s;
  };
  for (size_t i = 0; i < o.t_targets.size(); ++i) study_options(i);
  CheckOutputPaths({{"--csv", o.csv}, {"--trace", o.trace}, {"--plot", o.plot}}, {});
  if (!o.plot.empty()) {
    const std::string ext = std::filesystem::path(o.plot).extension().string();
    IDENT_REQUIRE(ext == ".svg" || ext == ".png", "--plot file '{}': need a .svg or .png name", o.plot);
  }
  // Each output goes to a temporary file, renamed onto its name once all of them are complete
  // (cli/output_file.h); the tables are printed after that, so a failed write leaves stdout empty.
  std::optional<OutputFile> csv_file, trace_file, plot_file;
  if (!o.csv.empty()) csv_file.emplace(o.csv, "--csv file");
  if (!o.trace.empty()) trace_file.emplace(o.trace, "--trace file");
  if (!o.plot.empty()) plot_file.emplace(o.plot, "--plot file");
  std::vector<MemsStudyResult> results;
  Progress progress("mems");  // on stderr after 2 s: the studies (one per --t-mean value)
  for (size_t i = 0; i < o.t_targets.size(); ++i) {
    results.push_back(RunMemsStudy(study_options(i)));
    progress.Report(static_cast<long>(i + 1), static_cast<long>(o.t_targets.size()), "studies");
  }
  // Fig. 9 analogue.
  std::ostringstream report;
  std::string grid_sizes;
  for (const auto& r : results)
    grid_sizes += fmt::format("{}{}x{}", grid_sizes.empty() ? "" : ",", r.grid_points, r.grid_points);
  report << fmt::format("MEMS accelerometer (h = {}, sigma^2 = 1, threshold 1, {} steps, {} grid)\n", o.h, o.steps,
                        grid_sizes);
  report << "RMS velocity error (calibration = predicted variance / mean squared error)\n";
  report << fmt::format("{:>8} {:>7}", "t_mean", "events");
  for (const auto& [col, name] : kColumns) report << fmt::format(" {:>17}", col);
  report << "\n";
  for (const auto& r : results) {
    report << fmt::format("{:8.3f} {:7d}", r.t_mean, r.events);
    for (const auto& [col, name] : kColumns) {
      const auto& ob = r.Get(name);
      report << fmt::format(" {:8.4f} ({:5.2f})", ob.rms, ob.calibration);
    }
    report << "\n";
  }
  // The calibration is a ratio of two averages over a few events: its sampling error, beside the figure.
  report << "calibration +- jackknife standard error (10 contiguous blocks of each run)\n";
  report << fmt::format("{:>8} {:>15} {:>15} {:>15}\n", "t_mean", "grid", "tuned_kalman", "lc_gaussian");
  for (const auto& r : results) {
    report << fmt::format("{:8.3f}", r.t_mean);
    for (const char* name : {"grid", "tuned_kalman", "lc_truncated"})
      report << fmt::format(" {:>15}",
                            fmt::format("{:.2f} +- {:.2f}", r.Get(name).calibration, r.Get(name).calibration_se));
    report << "\n";
  }
  report << fmt::format(
      "sigma_o = {:.4f} (p11 = 1/sqrt 3), bound: sigma_M^2 = (2 h v_ref)^2/3; lc_gaussian = "
      "lc_truncated: every reading exact, Gaussian restricted to the current reading's interval, "
      "no sigma_o\n",
      results.front().sigma_o);
  // The reference grid per rate: its size and the refinement check against the coarser grid.
  report << fmt::format(
      "grid reference: points per axis, mean var(x2), relative moment difference to the coarser "
      "grid (tolerance {})\n",
      o.grid_tolerance);
  report << fmt::format("{:>8} {:>7} {:>12} {:>8} {:>11} {:>10}\n", "t_mean", "points", "mean_var_x2", "coarser",
                        "difference", "converged");
  for (const auto& r : results)
    report << fmt::format("{:8.3f} {:7d} {:12.6f} {:8} {:11} {:>10}\n", r.t_mean, r.grid_points, r.grid_mean_variance,
                          r.grid_coarse_points > 0 ? std::to_string(r.grid_coarse_points) : "-",
                          r.grid_coarse_points > 0 ? fmt::format("{:.4f}", r.grid_difference) : "-",
                          r.grid_coarse_points > 0 ? (r.grid_converged ? "yes" : "no") : "-");
  long truncated_failures = 0, truncated_projection_failures = 0;
  for (const auto& r : results) {
    truncated_failures += r.truncated_failures;
    truncated_projection_failures += r.truncated_projection_failures;
  }
  report << fmt::format(
      "lc_truncated: Gaussian restricted to the current reading's interval (assumed-density "
      "filter); rectangles without mass {}, projections without a parent {}\n",
      truncated_failures, truncated_projection_failures);
  if (csv_file) {
    std::string f = "t_mean,t_target,events";
    for (const auto& [col, name] : kColumns) f += ",rms_" + col;
    for (const auto& [col, name] : kColumns) f += ",calibration_" + col;
    for (const auto& [col, name] : kColumns) f += ",calibration_se_" + col;
    f += ",grid_points,grid_coarse_points,grid_difference,grid_converged,grid_mean_var";
    f += "\n";
    for (size_t i = 0; i < results.size(); ++i) {
      const auto& r = results[i];
      f += fmt::format("{:.6g},{:.6g},{}", r.t_mean, o.t_targets[i], r.events);
      for (const auto& [col, name] : kColumns) f += fmt::format(",{:.6g}", r.Get(name).rms);
      for (const auto& [col, name] : kColumns) f += fmt::format(",{:.6g}", r.Get(name).calibration);
      for (const auto& [col, name] : kColumns) f += fmt::format(",{:.6g}", r.Get(name).calibration_se);
      f += fmt::format(",{},{},{},{},{:.6g}", r.grid_points, r.grid_coarse_points,
                       r.grid_coarse_points > 0 ? fmt::format("{:.6g}", r.grid_difference) : "",
                       r.grid_coarse_points > 0 ? (r.grid_converged ? "1" : "0") : "", r.grid_mean_variance);
      f += "\n";
    }
    csv_file->Write(f);
  }
  const MemsTrace& tr = results.front().trace;
  if (trace_file) {
    trace_file->Write("t,x1,y,var_grid,var_tuned_kalman,var_lc_gaussian,var_bound\n");
    for (size_t k = 0; k < tr.t.size(); ++k)
      trace_file->Write(fmt::format("{:.6g},{:.6g},{},{:.6g},{:.6g},{:.6g},{:.6g}\n", tr.t[k], tr.x1[k], tr.y[k],
                                    tr.var_grid[k], tr.var_tuned_kalman[k], tr.var_lc_gaussian[k], tr.var_bound[k]));
  }
  if (plot_file) {
    PlotPanel fig9{.title = "Fig. 9: RMS velocity error vs mean time between events",
                   .xlabel = "t_mean",
                   .ylabel = "RMS x2 error",
                   .series = {}};
    for (const auto& [col, name] : {std::pair<std::string, std::string>{"grid", "grid"},
                                    {"tuned Kalman", "tuned_kalman"},
                                    {"LC Gaussian", "lc_truncated"},
                                    {"bound", "bound"}}) {
      PlotSeries s{col, {}, {}};
      for (const auto& r : results) {
        s.x.push_back(r.t_mean);
        s.y.push_back(r.Get(name).rms);
      }
      fig9.series.push_back(std::move(s));
    }
    PlotPanel fig8{.title = fmt::format("Fig. 8: velocity variance, t_mean = {:.2f}", results.front().t_mean),
                   .xlabel = "t",
                   .ylabel = "var x2",
                   .series = {}};
    const size_t first = tr.t.size() / 10, last = std::min(tr.t.size(), first + static_cast<size_t>(10 / o.h));
    auto window = [&](const std::string& title, const std::vector<double>& v) {
      PlotSeries s{title, {}, {}};
      for (size_t k = first; k < last; ++k) {
        s.x.push_back(tr.t[k]);
        s.y.push_back(v[k]);
      }
      return s;
    };
    fig8.series.push_back(window("grid", tr.var_grid));
    fig8.series.push_back(window("tuned Kalman", tr.var_tuned_kalman));
    fig8.series.push_back(window("LC Gaussian", tr.var_lc_gaussian));
    fig8.series.push_back(window("approximate bound", tr.var_bound));
    RenderPlot(*plot_file, {fig9, fig8});
  }
  for (std::optional<OutputFile>* f : {&csv_file, &trace_file, &plot_file})
    if (*f) (*f)->Close();
  for (std::optional<OutputFile>* f : {&csv_file, &trace_file, &plot_file})
    if (*f) (*f)->Commit();
  std::cout << report.str();
}

}  // namespace

void AddMemsCommand(CLI::App& app) {
  auto opts = std::make_shared<MemsCommandOptions>();
  CLI::App* cmd = app.add_subcommand("mems", "MEMS accelerometer study (Henningsson & Astrom 2006, sec. V)");
  cmd->add_option("--t-mean", opts->t_targets, "target mean times between events (control law), comma separated")
      ->delimiter(',')
      ->capture_default_str();
  cmd->add_option("--steps", opts->steps, "simulated steps per rate (first 10 % are burn-in)")->capture_default_str();
  cmd->add_option("--seed", opts->seed, "random seed (rate i uses seed + i)")->capture_default_str();
  cmd->add_option("--grid-points", opts->grid_points,
                  "grid observer points per axis (the first grid of the refinement check when --grid-tolerance > 0)")
      ->capture_default_str();
  cmd->add_option("--grid-tolerance", opts->grid_tolerance,
                  "refine the grid (x1.5 per axis) until its moments agree with the next finer grid to this relative "
                  "difference; 0 = the --grid-points grid unchecked")
      ->capture_default_str();
  cmd->add_option("--h", opts->h, "sampling period")->capture_default_str();
  cmd->add_option("--ep-window", opts->ep_window, "lc_window: readings refined jointly by sliding-window EP")
      ->capture_default_str();
  cmd->add_option("--csv", opts->csv, "write the Fig. 9 table (one row per rate)");
  cmd->add_option("--trace", opts->trace, "write the Fig. 8 variance traces of the first rate (CSV)");
  cmd->add_option("--plot", opts->plot, "render Fig. 9 and Fig. 8 with gnuplot (*.svg or *.png)");
  cmd->callback([opts] { RunMems(*opts); });
}

}  // namespace ident::cli
