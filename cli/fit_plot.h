// The figure of `ident fit --plot FILE.svg|png` (cli/gnuplot.h renders it), panels stacked:
//   1. validation: measured output and the one-step and simulated outputs, in the data's units (the
//      detrending means added back); the measured output thick and dark under the thinner predictions;
//   2. estimation: the parameter trajectories θ̂(t), the y range fitted to the part after the start-up;
//   3. the robust weight νβ(t) of each update, low weights (discounted samples) marked (not for rls,
//      whose weights are all 1);
//   4. the validation one-step residuals' correlations r_ee(τ) and r_eu(τ) with the 99 % band
//      (ident/workflow/residual_analysis.h), when the fit has them.
//
// Example:
//   ParameterHistory history;        // filled from workflow::FitOptions::on_update
//   OutputFile out("fit.png", "--plot file");
//   PlotFit(out, record_fit, *source, history);
//   out.Commit();
#pragma once

#include <string>
#include <vector>

#include "cli/gnuplot.h"
#include "cli/output_file.h"
#include "ident/workflow/data_source.h"
#include "ident/workflow/fit_record.h"

namespace ident::cli {

struct ParameterHistory {
  std::vector<double> t;                   // 1-based row of each update
  std::vector<std::vector<double>> theta;  // theta[i][k]: entry i after update k
  std::vector<double> weight;              // νβ of update k (NaN where the estimator reports none)
};

// Updates of the start-up the θ̂(t) panel's y range leaves out: max(3ρ, 10 % of the updates), or up to the
// robust start of the lock-in monitor when that is later; at most half of the updates.
std::size_t StartUpUpdates(const workflow::RecordFit& fit, std::size_t updates, int num_parameters);

// The panels described above (exposed for tests).
std::vector<PlotPanel> FitPlotPanels(const workflow::RecordFit& fit, workflow::DataSource& source,
                                     const ParameterHistory& history);

// Renders into `out`'s temporary file (the caller commits it). Throws InvalidArgument (bad extension,
// gnuplot failing) naming the file.
void PlotFit(OutputFile& out, const workflow::RecordFit& fit, workflow::DataSource& source,
             const ParameterHistory& history);

}  // namespace ident::cli
