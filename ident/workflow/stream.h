// Estimating on rows as they arrive (`ident stream`): the recursion of `ident fit` (the same source,
// estimator and output cleaning, ident/workflow/internal/fit_steps.h) one row at a time, with a verdict
// per row. There is no split, no detrending (no means are known before the data) and one pass.
//
// After the last row of a record, Finish() takes the end-of-data steps `ident fit` takes (a start-up
// that still waits starts from every sample seen; the robust estimators weigh a restart from all kept
// samples, SafeStudentRegression::ReconsiderAtEnd), so that the estimate after Finish() is the one
// `ident fit --split 1 --detrend none` reports for the same rows and options, bit for bit — except for
// RLS with its default prior, which `fit` puts in the scale of the whole record (a stream starts from
// the unit-free flat prior, as `fit --exact` does).
//
// Example:
//   auto source = spec.MakeSource(reader.names(), "standard input");
//   auto estimator = MakeRegressionEstimator(settings, source->num_parameters());
//   ident::workflow::StreamEstimation stream(*source, *estimator, spec.Decision());
//   while (reader.Next(row)) { const StreamStep s = stream.Row(row); ... estimator->parameters() ... }
//   if (stream.Finish()) { ... a changed final estimate ... }
#pragma once

#include <memory>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "ident/regression/outlier_decision.h"
#include "ident/regression/regression_estimator.h"
#include "ident/workflow/data_source.h"

namespace ident::workflow {

namespace internal {
class Estimation;
}

enum class StreamStatus {
  kStartUp,   // no regression yet (the regressor's first rows), or the estimator's start window is filling
  kOk,        // updated, an inlier
  kOutlier,   // updated with a relative weight νβ below the model's outlier threshold (--clean-below)
  kRestart,   // updated, and the lock-in monitor restarted the estimator at this update
  kMissing,   // no update: this row or a row its regressor reaches back to has a missing value, or an
              // output cleaned as a gross error
  kRejected,  // no update: the estimator refused the sample (values too large, numerically unsafe)
  kEnd,       // the end-of-data steps changed the estimate (Finish)
};
std::string_view ToString(StreamStatus status);  // "start-up", "ok", "outlier", ...

struct StreamStep {
  long row = 0;  // 1-based data row
  StreamStatus status = StreamStatus::kStartUp;
  double weight = 0;  // β(t) of the update; NaN without one
  double nu = 0;      // ν(t) after it; NaN without one
};

class StreamEstimation {
 public:
  // `source` and `estimator` are used (and changed) in place; both must outlive this object. Throws
  // InvalidArgument for a batch estimator, which has no estimate before all data are in.
  StreamEstimation(DataSource& source, AnyRegressionEstimator& estimator, const OutlierDecision& decision);
  ~StreamEstimation();
  StreamEstimation(const StreamEstimation&) = delete;
  StreamEstimation& operator=(const StreamEstimation&) = delete;

  // One data row (all the record's columns; NaN = missing). The estimate afterwards is the estimator's.
  StreamStep Row(const Eigen::VectorXd& row);
  // A further experiment starts with the next row (`ident stream --experiment-column`): the regressors restart
  // as `ident fit` restarts them at an experiment (ident/workflow/experiments.h); the estimate carries on.
  void Restart();
  // The end of the data (see above). True if the estimate changed.
  bool Finish();
  long rows() const { return rows_; }

 private:
  DataSource& source_;
  AnyRegressionEstimator& estimator_;
  OutlierDecision decision_;
  std::unique_ptr<internal::Estimation> estimation_;
  std::vector<int> used_;
  int reach_;  // rows a regressor reaches back (t0)
  long rows_ = 0;
  long last_missing_ = -1;  // 0-based row of the last missing value in a used column
  long restarts_ = 0;
};

}  // namespace ident::workflow
