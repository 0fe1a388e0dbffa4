#include "ident/workflow/stream.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "common/error.h"
#include "ident/workflow/fit.h"
#include "ident/workflow/internal/fit_steps.h"

namespace ident::workflow {

std::string_view ToString(StreamStatus status) {
  switch (status) {
    case StreamStatus::kStartUp:
      return "start-up";
    case StreamStatus::kOk:
      return "ok";
    case StreamStatus::kOutlier:
      return "outlier";
    case StreamStatus::kRestart:
      return "restart";
    case StreamStatus::kMissing:
      return "missing";
    case StreamStatus::kRejected:
      return "rejected";
    case StreamStatus::kEnd:
      return "end";
  }
  return "unknown";
}

StreamEstimation::StreamEstimation(DataSource& source, AnyRegressionEstimator& estimator,
                                   const OutlierDecision& decision)
    : source_(source),
      estimator_(estimator),
      decision_(decision),
      used_(source.used_columns()),
      reach_(source.first_regression_index()) {
  IDENT_REQUIRE(estimator.kind() != "batch",
                "'{}' is a batch estimator (it solves on all samples at the end); a stream needs a recursive one "
                "(rls, cauchy, student, lc:...)",
                estimator.name());
  IDENT_REQUIRE(source.num_parameters() == estimator.num_parameters(), "the source has {} parameters, the estimator {}",
                source.num_parameters(), estimator.num_parameters());
  source_.ClearEstimate();  // ARMAX/OE/BJ: the first pass starts without an estimate, as in a fit
  FitOptions options;
  options.decision = decision;
  estimation_ = std::make_unique<internal::Estimation>(source_, estimator_, options);
  restarts_ = estimator_.restarts();
}

StreamEstimation::~StreamEstimation() = default;

StreamStep StreamEstimation::Row(const Eigen::VectorXd& row) {
  const long r = rows_++;
  for (int c : used_)
    if (std::isnan(row(c))) last_missing_ = r;
  const bool missing = last_missing_ >= 0 && r - last_missing_ <= reach_;
  const std::optional<StepReport> report =
      estimation_->Row(row, static_cast<int>(std::min<long>(r, std::numeric_limits<int>::max())));
  StreamStep step{.row = r + 1,
                  .status = StreamStatus::kStartUp,
                  .weight = std::numeric_limits<double>::quiet_NaN(),
                  .nu = std::numeric_limits<double>::quiet_NaN()};
  if (!report) {
    if (missing) step.status = StreamStatus::kMissing;
    return step;
  }
  if (!report->updated()) {
    // Skipped: the regressor holds an output cleaned as a gross error, which counts as missing.
    step.status = missing || report->status == StepStatus::kSkipped ? StreamStatus::kMissing : StreamStatus::kRejected;
    return step;
  }
  step.weight = report->weight;
  step.nu = report->nu;
  const long restarts = estimator_.restarts();
  if (restarts != restarts_) {
    restarts_ = restarts;
    step.status = StreamStatus::kRestart;
  } else if (estimator_.in_startup()) {
    step.status = StreamStatus::kStartUp;
  } else {
    step.status = decision_.Flags(*report) ? StreamStatus::kOutlier : StreamStatus::kOk;
  }
  return step;
}

void StreamEstimation::Restart() {
  estimation_->Restart();
  last_missing_ = -1;  // the missing values of the experiment before are out of reach
}

bool StreamEstimation::Finish() {
  // As internal::Estimation::Finish, without its identifiability checks (a stream reports every row).
  bool changed = estimator_.FinishStartup();
  if (!source_.uses_estimate()) changed = estimator_.ReconsiderAtEnd() || changed;
  return changed;
}

}  // namespace ident::workflow
