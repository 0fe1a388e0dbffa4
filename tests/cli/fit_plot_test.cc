// The panels of `ident fit --plot` (cli/fit_plot.h), checked without gnuplot: data units, the θ̂(t) range,
// the robust weights.
#include "cli/fit_plot.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "ident/io/mat_file.h"
#include "ident/workflow/fit_record.h"
#include "tests/support/test_data.h"

namespace ident::testing {
namespace {

struct PlottedFit {
  workflow::RecordFit fit;
  std::vector<cli::PlotPanel> panels;
};

// ARX(2,2,3) on the dryer record, split 0.5, mean detrending, as `ident fit dryer ... --plot` runs it.
PlottedFit FitDryer(const std::string& estimator) {
  workflow::FitRequest request;
  request.model.output = "y";
  request.model.inputs = {"u"};
  request.model.na = 2;
  request.model.nb = {2};
  request.model.nk = {3};
  request.estimator.estimator = estimator;
  io::DataTable table = io::ReadDataFile(DatasetPath("dryer.csv"));
  std::unique_ptr<workflow::DataSource> source = request.model.MakeSource(table.names, "dryer");
  workflow::FitPlan plan = workflow::PlanFit(request, source->num_parameters(), table.num_rows() / 2);
  cli::ParameterHistory history;
  history.theta.resize(4);
  plan.options.on_update = [&history](int row, const StepReport& step, const AnyRegressionEstimator& e) {
    history.t.push_back(row + 1);
    history.weight.push_back(step.nu * step.weight);
    for (int i = 0; i < 4; ++i) history.theta[static_cast<std::size_t>(i)].push_back(e.parameters()(i));
  };
  PlottedFit out{workflow::FitTable(std::move(table), *source, plan), {}};
  out.panels = cli::FitPlotPanels(out.fit, *source, history);
  return out;
}

const cli::PlotSeries& SeriesStartingWith(const cli::PlotPanel& panel, const std::string& title) {
  for (const cli::PlotSeries& s : panel.series)
    if (s.title.rfind(title, 0) == 0) return s;
  throw std::runtime_error("no series " + title + " in panel " + panel.title);
}

TEST(FitPlot, OutputPanelIsInTheDataUnits) {
  std::vector<std::string> names;
  const Eigen::MatrixXd csv = ReadCsvMatrix(DatasetPath("dryer.csv"), &names);  // t, u, y
  ASSERT_EQ(names[2], "y");
  // The estimation part's means, computed here from the file (rows 1-500).
  const double mu = csv.col(1).head(500).mean(), my = csv.col(2).head(500).mean();
  const PlottedFit f = FitDryer("rls");
  const Eigen::VectorXd& th = f.fit.result.theta;  // a1 a2 b1 b2: y = −a1 y(t−1) − a2 y(t−2) + b1 u(t−3) + b2 u(t−4)
  const cli::PlotSeries& measured = SeriesStartingWith(f.panels[0], "measured");
  const cli::PlotSeries& one_step = SeriesStartingWith(f.panels[0], "one-step");
  ASSERT_EQ(measured.x.size(), 500u);
  int checked = 0;
  for (std::size_t k = 0; k < measured.x.size(); ++k) {
    const int r = static_cast<int>(measured.x[k]) - 1;  // 0-based row
    EXPECT_NEAR(measured.y[k], csv(r, 2), 1e-12) << "row " << r + 1;
    if (!std::isfinite(one_step.y[k])) continue;
    const double predicted = my - th(0) * (csv(r - 1, 2) - my) - th(1) * (csv(r - 2, 2) - my) +
                             th(2) * (csv(r - 3, 1) - mu) + th(3) * (csv(r - 4, 1) - mu);
    EXPECT_NEAR(one_step.y[k], predicted, 1e-9) << "row " << r + 1;
    ++checked;
  }
  EXPECT_GE(checked, 490);
}

TEST(FitPlot, ParameterRangeLeavesOutTheStartUpAndRlsHasNoWeightPanel) {
  const PlottedFit f = FitDryer("rls");
  const cli::PlotPanel& theta = f.panels[1];
  ASSERT_TRUE(theta.yrange.has_value());
  double all_low = 0, all_high = 0;
  for (const cli::PlotSeries& s : theta.series) {
    const std::size_t start = cli::StartUpUpdates(f.fit, s.y.size(), 4);
    for (std::size_t k = 0; k < s.y.size(); ++k) {
      all_low = std::min(all_low, s.y[k]);
      all_high = std::max(all_high, s.y[k]);
      if (k >= start) {
        EXPECT_GT(s.y[k], theta.yrange->low);
        EXPECT_LT(s.y[k], theta.yrange->high);
      }
    }
  }
  // rls from a flat prior swings far during its first updates; the range is much narrower than that.
  EXPECT_LT(theta.yrange->high - theta.yrange->low, 0.5 * (all_high - all_low));
  EXPECT_LT(theta.yrange->high - theta.yrange->low, 3.0);  // the final a1 ≈ −1.27, a2 ≈ 0.39
  for (const cli::PlotPanel& p : f.panels) EXPECT_EQ(p.title.find("weight"), std::string::npos) << p.title;
}

TEST(FitPlot, CauchyWeightPanelMarksTheLowWeights) {
  const PlottedFit f = FitDryer("cauchy");
  const auto panel = std::find_if(f.panels.begin(), f.panels.end(),
                                  [](const cli::PlotPanel& p) { return p.title.find("weight") != std::string::npos; });
  ASSERT_NE(panel, f.panels.end());
  const cli::PlotSeries& low = SeriesStartingWith(*panel, "νβ <");
  const cli::PlotSeries& high = SeriesStartingWith(*panel, "νβ ≥");
  EXPECT_EQ(low.y.size() + high.y.size(), 496u);  // one weight per update (rows 5-500)
  EXPECT_GT(low.y.size(), 0u);
  for (double w : low.y) EXPECT_LT(w, 0.3);
  for (double w : high.y) EXPECT_GE(w, 0.3);
  // The residual panel's band is 2.58/√N.
  const cli::PlotSeries& band = SeriesStartingWith(f.panels.back(), "99 % band");
  EXPECT_NEAR(band.y[0], 2.5758 / std::sqrt(496.0), 1e-3);
}

}  // namespace
}  // namespace ident::testing
