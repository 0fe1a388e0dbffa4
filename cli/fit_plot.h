// The figure of `ident fit --plot FILE.svg|png`: measured vs one-step and simulated output on the
// validation part, and the parameter trajectories θ̂(t) during estimation (cli/gnuplot.h renders it).
//
// Example:
//   ParameterHistory history;        // filled from workflow::FitOptions::on_update
//   OutputFile out("fit.png", "--plot file");
//   PlotFit(out, prepared_table, validation, *source, theta, history);
//   out.Commit();
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "ident/io/csv.h"
#include "ident/workflow/data_source.h"
#include "ident/workflow/fit.h"
#include "cli/output_file.h"

namespace ident::cli {

struct ParameterHistory {
  std::vector<double> t;                   // 1-based row of each update
  std::vector<std::vector<double>> theta;  // theta[i][k]: entry i after update k
};

// Renders into `out`'s temporary file (the caller commits it). Throws InvalidArgument (bad extension,
// gnuplot failing) naming the file.
void PlotFit(OutputFile& out, const io::DataTable& data, workflow::Segment validation, workflow::DataSource& source,
             const Eigen::VectorXd& theta, const ParameterHistory& history);

}  // namespace ident::cli
