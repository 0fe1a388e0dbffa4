#include "cli/fit_plot.h"

#include <cmath>

#include "cli/gnuplot.h"

namespace ident::cli {

void PlotFit(OutputFile& out, const io::DataTable& data, workflow::Segment validation, workflow::DataSource& source,
             const Eigen::VectorXd& theta, const ParameterHistory& history) {
  const int rho = source.num_parameters();
  Eigen::VectorXd z(rho);
  PlotSeries measured{"measured", {}, {}}, one_step{"one-step prediction", {}, {}}, simulated{"simulation", {}, {}};
  // One-step: measured past outputs (as in workflow::Score).
  source.Reset();
  for (int r = validation.first; r < validation.first + validation.count; ++r) {
    const Eigen::VectorXd row = data.values.row(r).transpose();
    const double y = row(source.output_column());
    measured.x.push_back(r + 1);
    measured.y.push_back(y);
    one_step.x.push_back(r + 1);
    one_step.y.push_back(source.Regressor(row, z) ? theta.dot(z) : std::nan(""));
    source.PushOutput(y);
  }
  std::vector<PlotPanel> panels;
  PlotPanel output{"validation: measured and predicted output",
                   "row",
                   data.names[static_cast<std::size_t>(source.output_column())],
                   {}};
  output.series.push_back(measured);
  output.series.push_back(one_step);
  if (source.dynamic()) {
    // Simulation: the model's own past outputs after the first t0 measured samples (as in workflow::Score).
    source.Reset();
    const int t0 = source.first_regression_index();
    for (int r = validation.first; r < validation.first + validation.count; ++r) {
      const Eigen::VectorXd row = data.values.row(r).transpose();
      const double y = row(source.output_column());
      simulated.x.push_back(r + 1);
      if (source.Regressor(row, z)) {
        const double yhat = theta.dot(z);
        simulated.y.push_back(yhat);
        source.PushOutput(yhat);
      } else {
        simulated.y.push_back(std::nan(""));
        source.PushOutput(r - validation.first < t0 ? y : std::nan(""));
      }
    }
    output.series.push_back(simulated);
  }
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
