// The model's outputs on a segment of a prepared (split and detrended) table, as workflow::Score
// scores them: the one-step prediction θ'z(t) from measured past outputs, and (dynamic models) the
// simulated output, which feeds back the model's own past outputs after the first t0 measured samples.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "ident/io/csv.h"
#include "ident/workflow/data_source.h"
#include "ident/workflow/fit.h"
#include "models/arx.h"

namespace ident::workflow {

struct SegmentPredictions {
  std::vector<int> rows;           // 1-based rows of the record
  std::vector<double> measured;    // y
  std::vector<double> one_step;    // NaN where the segment has no regression (its first t0 rows, missing data)
  std::vector<double> simulation;  // empty for static models; NaN as above
};

// `source` is Reset() before each walk.
SegmentPredictions PredictSegment(const io::DataTable& data, Segment segment, DataSource& source,
                                  const Eigen::VectorXd& theta);

// k-step-ahead predictions ŷ(t | t−k) of an ARX model over a segment: the outputs after t−k are the
// model's own predictions, those up to t−k (and the segment's first t0, which have no regressor) measured.
// k = 1 is the one-step prediction of PredictSegment. NaN where the segment has no regression. Each experiment
// of the segment (io::DataTable::experiment_starts) is predicted on its own rows alone (both overloads).
std::vector<double> PredictKSteps(const io::DataTable& data, Segment segment, const models::ArxStructure& arx,
                                  int output_column, const std::vector<int>& input_columns,
                                  const Eigen::VectorXd& theta, int k);

// The same for any model whose regressors a DataSource forms (ARMAX, OE, Box–Jenkins and ARX): for each t,
// a copy of the source that has taken the measured outputs up to t−k takes its own predictions after t−k,
// so the noise model's future innovations are zero — the k-step predictor of the polynomial model (Ljung
// 1999, §3.2, eq. (3.31)). O(k·ρ) per row plus one copy of the source's state. `source` is Reset() first.
std::vector<double> PredictKSteps(const io::DataTable& data, Segment segment, const DataSource& source,
                                  const Eigen::VectorXd& theta, int k);

}  // namespace ident::workflow
