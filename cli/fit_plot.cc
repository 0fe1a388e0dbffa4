#include "cli/fit_plot.h"

#include <cmath>

#include "cli/gnuplot.h"
#include "ident/workflow/predictions.h"

namespace ident::cli {

void PlotFit(OutputFile& out, const io::DataTable& data, workflow::Segment validation, workflow::DataSource& source,
             const Eigen::VectorXd& theta, const ParameterHistory& history) {
  const int rho = source.num_parameters();
  const workflow::SegmentPredictions p = workflow::PredictSegment(data, validation, source, theta);
  const std::vector<double> rows(p.rows.begin(), p.rows.end());
  std::vector<PlotPanel> panels;
  PlotPanel output{"validation: measured and predicted output",
                   "row",
                   data.names[static_cast<std::size_t>(source.output_column())],
                   {}};
  output.series.push_back({"measured", rows, p.measured});
  output.series.push_back({"one-step prediction", rows, p.one_step});
  if (source.dynamic()) output.series.push_back({"simulation", rows, p.simulation});
  panels.push_back(output);
  PlotPanel parameters{"estimation: parameter trajectories", "row", "estimate", {}};
  const std::vector<std::string> names = source.parameter_names();
  for (int i = 0; i < rho && i < static_cast<int>(history.theta.size()); ++i)
    parameters.series.push_back(
        {names[static_cast<std::size_t>(i)], history.t, history.theta[static_cast<std::size_t>(i)]});
  if (!history.t.empty()) panels.push_back(parameters);
  RenderPlot(out, panels);
}

}  // namespace ident::cli
