#include "cli/fit_plot.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "ident/workflow/predictions.h"

namespace ident::cli {
namespace {

constexpr double kLowWeightDefault = 0.3;  // the default --lock-in-threshold

std::string FitPercent(double p) { return std::isfinite(p) ? fmt::format("{:.1f} %", p) : "undefined"; }

// The output column's detrending mean (0 without detrending).
double OutputMean(const workflow::RecordFit& fit, const std::string& output) {
  for (const auto& [column, mean] : fit.detrend_means)
    if (column == output) return mean;
  return 0;
}

PlotPanel OutputPanel(const workflow::RecordFit& fit, workflow::DataSource& source) {
  const io::DataTable& data = fit.prepared;
  const workflow::SegmentPredictions p = workflow::PredictSegment(data, fit.validation, source, fit.result.theta);
  const std::string& output = data.names[static_cast<std::size_t>(source.output_column())];
  const double mean = OutputMean(fit, output);
  auto physical = [mean](std::vector<double> v) {
    for (double& x : v) x += mean;
    return v;
  };
  const std::vector<double> rows(p.rows.begin(), p.rows.end());
  PlotPanel panel{fmt::format("validation: {}, {}", fit.result.structure, fit.result.estimator), "row", output, {}};
  if (!rows.empty()) panel.xrange = PlotRange{rows.front() - 0.5, rows.back() + 0.5};
  // A dynamic model's output is a signal (thick line under the thin predictions); a static one's are samples.
  const bool dynamic = source.dynamic();
  panel.series.push_back({"measured", rows, physical(p.measured),
                          dynamic ? "lines lw 3.5 lc rgb '#8c8c8c'" : "points pt 7 ps 1.4 lc rgb '#606060'"});
  panel.series.push_back(
      {fmt::format("one-step (fit {})", FitPercent(fit.result.validation.one_step)), rows, physical(p.one_step),
       dynamic ? "lines lw 1.2 lc rgb '#0050c0'" : "linespoints lw 1.2 pt 6 ps 1.2 lc rgb '#0050c0'"});
  if (dynamic) {
    const auto& v = fit.result.validation;
    panel.series.push_back({fmt::format("simulation (fit {})", v.simulation ? FitPercent(*v.simulation) : "undefined"),
                            rows, physical(p.simulation), "lines lw 1.2 lc rgb '#d03000'"});
  }
  return panel;
}

PlotPanel ParameterPanel(const workflow::RecordFit& fit, workflow::DataSource& source, const ParameterHistory& h) {
  const int rho = source.num_parameters();
  const std::size_t updates = h.t.size();
  const std::size_t start = StartUpUpdates(fit, updates, rho);
  PlotPanel panel{
      fmt::format("estimation: parameter trajectories θ̂(t), y range after the start-up ({} updates)", start),
      "row",
      "estimate",
      {}};
  if (updates > 0) panel.xrange = PlotRange{h.t.front() - 0.5, h.t.back() + 0.5};
  const std::vector<std::string> names = source.parameter_names();
  double low = std::numeric_limits<double>::infinity(), high = -low;
  for (int i = 0; i < rho && i < static_cast<int>(h.theta.size()); ++i) {
    const std::vector<double>& theta = h.theta[static_cast<std::size_t>(i)];
    panel.series.push_back({names[static_cast<std::size_t>(i)], h.t, theta, "lines lw 1.5"});
    for (std::size_t k = start; k < theta.size(); ++k)
      if (std::isfinite(theta[k])) {
        low = std::min(low, theta[k]);
        high = std::max(high, theta[k]);
      }
  }
  if (low <= high) {
    const double margin = std::max(0.1 * (high - low), 1e-9 * std::max(1.0, std::max(std::abs(low), std::abs(high))));
    panel.yrange = PlotRange{low - margin, high + margin};
  }
  return panel;
}

// Empty (no panel) when no update has a weight other than 1.
std::optional<PlotPanel> WeightPanel(const workflow::RecordFit& fit, const ParameterHistory& h) {
  const double threshold = fit.result.lock_in ? fit.result.lock_in->threshold : kLowWeightDefault;
  PlotSeries normal{fmt::format("νβ ≥ {:g}", threshold), {}, {}, "points pt 7 ps 0.35 lc rgb '#0050c0'"};
  PlotSeries low{fmt::format("νβ < {:g}: discounted", threshold), {}, {}, "points pt 7 ps 0.8 lc rgb '#e00000'"};
  bool informative = false;
  double top = 1;
  for (std::size_t k = 0; k < h.weight.size() && k < h.t.size(); ++k) {
    const double w = h.weight[k];
    if (!std::isfinite(w)) continue;
    informative = informative || std::abs(w - 1) > 1e-9;
    top = std::max(top, w);
    PlotSeries& s = w < threshold ? low : normal;
    s.x.push_back(h.t[k]);
    s.y.push_back(w);
  }
  if (!informative) return std::nullopt;
  PlotPanel panel{"estimation: robust weight νβ(t) of each sample (1: as least squares)", "row", "νβ", {}};
  panel.xrange = PlotRange{h.t.front() - 0.5, h.t.back() + 0.5};
  panel.yrange = PlotRange{0, 1.05 * top};
  panel.series.push_back({"", {h.t.front(), h.t.back()}, {1, 1}, "lines lw 1 dt 2 lc rgb 'black'"});
  if (!normal.y.empty()) panel.series.push_back(std::move(normal));
  if (!low.y.empty()) panel.series.push_back(std::move(low));
  return panel;
}

PlotPanel ResidualPanel(const workflow::ResidualAnalysis& a) {
  PlotPanel panel{
      fmt::format("validation one-step residuals: correlations (N = {})", a.samples), "lag τ", "correlation", {}};
  const int lags = static_cast<int>(a.autocorrelation.size());
  panel.xrange = PlotRange{-0.5, lags + 0.5};
  double top = a.band;
  for (double r : a.autocorrelation) top = std::max(top, std::abs(r));
  for (const std::vector<double>& c : a.cross_correlation)
    for (double r : c) top = std::max(top, std::abs(r));
  panel.yrange = PlotRange{-1.15 * top, 1.15 * top};
  std::vector<double> tau;
  for (int k = 1; k <= lags; ++k) tau.push_back(k);
  panel.series.push_back({fmt::format("99 % band ±{:.3f}", a.band),
                          {-0.5, lags + 0.5},
                          {a.band, a.band},
                          "lines lw 1.2 dt 2 lc rgb 'black'"});
  panel.series.push_back({"", {-0.5, lags + 0.5}, {-a.band, -a.band}, "lines lw 1.2 dt 2 lc rgb 'black'"});
  panel.series.push_back({"r_ee(τ), τ ≥ 1", tau, a.autocorrelation, "impulses lw 3 lc rgb '#0050c0'"});
  for (std::size_t i = 0; i < a.input_names.size(); ++i) {
    std::vector<double> x;
    for (std::size_t k = 0; k < a.cross_correlation[i].size(); ++k)
      x.push_back(static_cast<double>(k) +
                  0.2 * static_cast<double>(i + 1) / static_cast<double>(a.input_names.size()));
    panel.series.push_back({fmt::format("r_e,{}(τ), τ ≥ 0", a.input_names[i]), x, a.cross_correlation[i],
                            fmt::format("points pt 7 ps 0.7 lc {}", i + 3)});
  }
  return panel;
}

}  // namespace

std::size_t StartUpUpdates(const workflow::RecordFit& fit, std::size_t updates, int num_parameters) {
  std::size_t start = std::max<std::size_t>(3 * static_cast<std::size_t>(num_parameters), updates / 10);
  if (fit.result.lock_in && fit.result.lock_in->start_update > 0)
    start = std::max(start, static_cast<std::size_t>(fit.result.lock_in->start_update));
  return std::min(start, updates / 2);
}

std::vector<PlotPanel> FitPlotPanels(const workflow::RecordFit& fit, workflow::DataSource& source,
                                     const ParameterHistory& history) {
  std::vector<PlotPanel> panels{OutputPanel(fit, source)};
  if (!history.t.empty()) {
    panels.push_back(ParameterPanel(fit, source, history));
    if (std::optional<PlotPanel> w = WeightPanel(fit, history)) panels.push_back(std::move(*w));
  }
  if (fit.residuals) panels.push_back(ResidualPanel(*fit.residuals));
  return panels;
}

void PlotFit(OutputFile& out, const workflow::RecordFit& fit, workflow::DataSource& source,
             const ParameterHistory& history) {
  RenderPlot(out, FitPlotPanels(fit, source, history), PlotSize{.width = 1100, .height_per_panel = 300});
}

}  // namespace ident::cli
