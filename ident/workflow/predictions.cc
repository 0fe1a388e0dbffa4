#include "ident/workflow/predictions.h"

#include <cmath>
#include <limits>

namespace ident::workflow {

SegmentPredictions PredictSegment(const io::DataTable& data, Segment segment, DataSource& source,
                                  const Eigen::VectorXd& theta) {
  constexpr double kNone = std::numeric_limits<double>::quiet_NaN();
  SegmentPredictions p;
  Eigen::VectorXd z(source.num_parameters());
  Eigen::VectorXd row(data.values.cols());
  source.Reset();
  for (int r = segment.first; r < segment.first + segment.count; ++r) {
    row = data.values.row(r).transpose();
    const double y = row(source.output_column());
    p.rows.push_back(r + 1);
    p.measured.push_back(y);
    p.one_step.push_back(source.Regressor(row, z) ? theta.dot(z) : kNone);
    source.PushOutput(y);
  }
  if (!source.dynamic()) return p;
  source.Reset();
  const int t0 = source.first_regression_index();
  for (int r = segment.first; r < segment.first + segment.count; ++r) {
    row = data.values.row(r).transpose();
    if (source.Regressor(row, z)) {
      const double y_hat = theta.dot(z);
      p.simulation.push_back(y_hat);
      source.PushOutput(y_hat);
    } else {
      p.simulation.push_back(kNone);
      source.PushOutput(r - segment.first < t0 ? row(source.output_column()) : kNone);
    }
  }
  return p;
}

}  // namespace ident::workflow
