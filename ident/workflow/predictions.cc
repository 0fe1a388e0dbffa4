#include "ident/workflow/predictions.h"

#include <cmath>
#include <limits>
#include <memory>

namespace ident::workflow {
namespace {

// The segment's experiments (io::DataTable::experiment_starts within it) predicted one at a time by
// predict(piece), concatenated; an empty vector when the segment holds one experiment only.
template <class Predict>
std::vector<double> PerExperiment(const io::DataTable& data, Segment segment, Predict predict) {
  std::vector<double> out;
  int first = segment.first;
  const int end = segment.first + segment.count;
  for (int r = segment.first + 1; r <= end; ++r)
    if (r == end || data.StartsExperiment(r)) {
      if (r == end && first == segment.first) return {};
      const std::vector<double> piece = predict(Segment{first, r - first});
      out.insert(out.end(), piece.begin(), piece.end());
      first = r;
    }
  return out;
}

}  // namespace

SegmentPredictions PredictSegment(const io::DataTable& data, Segment segment, DataSource& source,
                                  const Eigen::VectorXd& theta) {
  constexpr double kNone = std::numeric_limits<double>::quiet_NaN();
  SegmentPredictions p;
  Eigen::VectorXd z(source.num_parameters());
  Eigen::VectorXd row(data.values.cols());
  source.Reset();
  source.SetEstimate(theta);
  for (int r = segment.first; r < segment.first + segment.count; ++r) {
    if (r > segment.first && data.StartsExperiment(r)) source.Restart();
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
  int experiment_first = segment.first;  // the simulation restarts from each experiment's own outputs
  for (int r = segment.first; r < segment.first + segment.count; ++r) {
    if (r > segment.first && data.StartsExperiment(r)) {
      source.Restart();
      experiment_first = r;
    }
    row = data.values.row(r).transpose();
    if (source.Regressor(row, z)) {
      const double y_hat = theta.dot(z);
      p.simulation.push_back(y_hat);
      source.PushOutput(y_hat);
    } else {
      p.simulation.push_back(kNone);
      source.PushOutput(r - experiment_first < t0 ? row(source.output_column()) : kNone);
    }
  }
  return p;
}

std::vector<double> PredictKSteps(const io::DataTable& data, Segment segment, const models::ArxStructure& arx,
                                  int output_column, const std::vector<int>& input_columns,
                                  const Eigen::VectorXd& theta, int k) {
  std::vector<double> experiments = PerExperiment(data, segment, [&](Segment piece) {
    return PredictKSteps(data, piece, arx, output_column, input_columns, theta, k);
  });
  if (!experiments.empty()) return experiments;
  constexpr double kNone = std::numeric_limits<double>::quiet_NaN();
  const int t0 = arx.first_regression_index();
  const int first = segment.first, end = segment.first + segment.count;
  std::vector<double> out(static_cast<std::size_t>(segment.count), kNone);
  std::vector<double> own(static_cast<std::size_t>(k));  // ỹ(t−k+1) … ỹ(t)
  Eigen::VectorXd z(arx.num_parameters());
  auto y_at = [&](int t, int j) {  // ỹ(j) while predicting ŷ(t)
    return j <= t - k || j < first + t0 ? data.values(j, output_column)
                                        : own[static_cast<std::size_t>(j - (t - k + 1))];
  };
  for (int t = first + t0; t < end; ++t) {
    for (int j = std::max(t - k + 1, first + t0); j <= t; ++j) {
      int i = 0;
      for (int lag = 1; lag <= arx.na(); ++lag) z(i++) = -y_at(t, j - lag);
      for (std::size_t in = 0; in < input_columns.size(); ++in)
        for (int l = 0; l < arx.nb()[in]; ++l) z(i++) = data.values(j - arx.nk()[in] - l, input_columns[in]);
      own[static_cast<std::size_t>(j - (t - k + 1))] = theta.dot(z);
    }
    out[static_cast<std::size_t>(t - first)] = own[static_cast<std::size_t>(k - 1)];
  }
  return out;
}

std::vector<double> PredictKSteps(const io::DataTable& data, Segment segment, const DataSource& source,
                                  const Eigen::VectorXd& theta, int k) {
  std::vector<double> experiments =
      PerExperiment(data, segment, [&](Segment piece) { return PredictKSteps(data, piece, source, theta, k); });
  if (!experiments.empty()) return experiments;
  constexpr double kNone = std::numeric_limits<double>::quiet_NaN();
  const int first = segment.first, end = segment.first + segment.count;
  std::vector<double> out(static_cast<std::size_t>(segment.count), kNone);
  std::unique_ptr<DataSource> measured = source.Clone();  // has taken the measured outputs up to t−k
  measured->Reset();
  measured->SetEstimate(theta);
  const int t0 = measured->first_regression_index(), output = measured->output_column();
  Eigen::VectorXd z(measured->num_parameters());
  Eigen::VectorXd row(data.values.cols());
  int taken = first;  // rows the measured source has taken
  for (int t = first; t < end; ++t) {
    for (; taken <= t - k; ++taken) {
      row = data.values.row(taken).transpose();
      measured->Regressor(row, z);
      measured->PushOutput(row(output));
    }
    std::unique_ptr<DataSource> ahead = measured->Clone();
    double y_hat = kNone;
    for (int j = taken; j <= t; ++j) {
      row = data.values.row(j).transpose();
      y_hat = ahead->Regressor(row, z) ? theta.dot(z) : kNone;
      ahead->PushOutput(std::isfinite(y_hat) ? y_hat : j - first < t0 ? row(output) : kNone);
    }
    out[static_cast<std::size_t>(t - first)] = y_hat;
  }
  return out;
}

}  // namespace ident::workflow
