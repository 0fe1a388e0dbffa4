// The figure of `ident fit --plot FILE.svg|png`: measured vs one-step and simulated output on the
// validation part, and the parameter trajectories θ̂(t) during estimation (tools/gnuplot.h renders it).
//
// Example:
//   ParameterHistory history;        // filled from FitOptions::on_update
//   PlotFit("fit.png", prepared_table, validation, *source, theta, history);
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "ident/io/csv.h"
#include "tools/data_source.h"
#include "tools/fit.h"

namespace ident::tools {

struct ParameterHistory {
  std::vector<double> t;                 // 1-based row of each update
  std::vector<std::vector<double>> theta;  // theta[i][k]: entry i after update k
};

// Throws InvalidArgument (bad extension, gnuplot failing) naming the file.
void PlotFit(const std::string& path, const io::DataTable& data, Segment validation, DataSource& source,
             const Eigen::VectorXd& theta, const ParameterHistory& history);

}  // namespace ident::tools
