#include "tools/fit.h"

#include <cmath>

#include <Eigen/Eigenvalues>
#include <fmt/format.h>

#include "ident/common/error.h"

namespace ident::tools {

std::pair<Segment, Segment> PrepareData(io::DataTable& data, const DataSource& source, const FitOptions& options) {
  IDENT_REQUIRE(std::isfinite(options.split) && options.split > 0 && options.split <= 1,
                "split = {}; need 0 < split <= 1", options.split);
  const int n = data.num_rows();
  const int n_est = options.split == 1 ? n : static_cast<int>(std::floor(options.split * n));
  const Segment estimation{0, n_est};
  const Segment validation = options.split == 1 ? Segment{0, n} : Segment{n_est, n - n_est};
  const int t0 = source.first_regression_index();
  const int rho = source.num_parameters();
  IDENT_REQUIRE(estimation.count - t0 >= rho + 1,
                "{}: the estimation part has {} rows; {} with {} parameters needs at least {} (lower the orders or "
                "raise --split)",
                data.source, estimation.count, source.structure(), rho, t0 + rho + 1);
  IDENT_REQUIRE(validation.count - t0 >= 2,
                "{}: the validation part has {} rows; {} needs at least {} (lower --split)", data.source,
                validation.count, source.structure(), t0 + 2);
  if (options.detrend == Detrend::kMean) {
    for (int c : source.used_columns()) {
      double sum = 0;
      int count = 0;
      for (int r = 0; r < n_est; ++r)
        if (const double v = data.values(r, c); !std::isnan(v)) {
          sum += v;
          ++count;
        }
      if (count > 0) data.values.col(c).array() -= sum / count;
    }
  }
  return {estimation, validation};
}

void WriteTraceHeader(std::FILE* trace, int num_parameters) {
  fmt::print(trace, "t,nu,beta,pred_err");
  for (int i = 1; i <= num_parameters; ++i) fmt::print(trace, ",theta{}", i);
  fmt::print(trace, ",Dy\n");
}

std::pair<int, int> Estimate(const io::DataTable& data, Segment segment, DataSource& source,
                             AnyRegressionEstimator& estimator, std::FILE* trace,
                             const OutlierDecision& decision,
                             const std::function<void(int row, const AnyRegressionEstimator&)>& on_update) {
  const int rho = source.num_parameters();
  Eigen::VectorXd z(rho);
  Eigen::MatrixXd ZtZ = Eigen::MatrixXd::Zero(rho, rho);
  int updates = 0, rejected = 0;
  source.Reset();
  for (int r = segment.first; r < segment.first + segment.count; ++r) {
    const Eigen::VectorXd row = data.values.row(r).transpose();
    const double y = row(source.output_column());
    bool flagged = false;
    double y_hat = std::nan(""), scale = std::nan("");
    if (source.Regressor(row, z)) {
      const StepReport report = estimator.Update(y, z);
      flagged = decision.Flags(report);
      if (flagged) {
        y_hat = y - report.prediction_error;
        scale = estimator.noise_std();
      }
      if (report.updated()) {
        ++updates;
        ZtZ.selfadjointView<Eigen::Lower>().rankUpdate(z);
        if (on_update) on_update(r, estimator);
        if (trace) {
          const Eigen::VectorXd theta = estimator.parameters();
          fmt::print(trace, "{},{:.17g},{:.17g},{:.17g}", r + 1, report.nu, report.weight, report.prediction_error);
          for (int i = 0; i < rho; ++i) fmt::print(trace, ",{:.17g}", theta(i));
          fmt::print(trace, ",{:.17g}\n", estimator.Dy());
        }
      } else {
        ++rejected;
      }
    }
    source.PushCheckedOutput(y, y_hat, scale, flagged);
  }
  // Identifiability: every regressor must vary and none may be a combination of the others.
  const std::vector<std::string> names = source.parameter_names();
  Eigen::MatrixXd G = ZtZ.selfadjointView<Eigen::Lower>();
  const Eigen::VectorXd scale = G.diagonal().cwiseSqrt();
  for (int i = 0; i < rho; ++i)
    IDENT_REQUIRE(scale(i) > 0, "{}: regressor '{}' is identically zero over the estimation part (constant input "
                  "after detrending?); the model is not identifiable", data.source, names[i]);
  const Eigen::MatrixXd C = scale.cwiseInverse().asDiagonal() * G * scale.cwiseInverse().asDiagonal();
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(C);
  IDENT_REQUIRE(eig.eigenvalues()(0) > 1e-12 * rho,
                "{}: the regressors are collinear over the estimation part (smallest eigenvalue of their "
                "correlation matrix {:.3g}); the model is not identifiable",
                data.source, eig.eigenvalues()(0));
  return {updates, rejected};
}

FitScores Score(const io::DataTable& data, Segment segment, DataSource& source, const Eigen::VectorXd& theta) {
  const int rho = source.num_parameters();
  Eigen::VectorXd z(rho);
  auto fit = [](const std::vector<double>& y, const std::vector<double>& yhat, double& rms) {
    double mean = 0;
    for (double v : y) mean += v;
    mean /= static_cast<double>(y.size());
    double err = 0, dev = 0;
    for (std::size_t i = 0; i < y.size(); ++i) {
      err += (y[i] - yhat[i]) * (y[i] - yhat[i]);
      dev += (y[i] - mean) * (y[i] - mean);
    }
    rms = std::sqrt(err / static_cast<double>(y.size()));
    return 100.0 * (1.0 - std::sqrt(err) / std::sqrt(dev));
  };
  FitScores scores;
  std::vector<double> y_meas, y_pred;
  source.Reset();
  for (int r = segment.first; r < segment.first + segment.count; ++r) {
    const Eigen::VectorXd row = data.values.row(r).transpose();
    const double y = row(source.output_column());
    if (source.Regressor(row, z) && std::isfinite(y) && z.allFinite()) {
      y_meas.push_back(y);
      y_pred.push_back(theta.dot(z));
    }
    source.PushOutput(y);
  }
  IDENT_REQUIRE(y_meas.size() >= 2, "{}: fewer than 2 validation samples can be scored", data.source);
  scores.scored = static_cast<int>(y_meas.size());
  scores.one_step = fit(y_meas, y_pred, scores.rms_one_step);
  if (source.dynamic()) {
    y_meas.clear();
    y_pred.clear();
    source.Reset();
    const int t0 = source.first_regression_index();
    for (int r = segment.first; r < segment.first + segment.count; ++r) {
      const Eigen::VectorXd row = data.values.row(r).transpose();
      const double y = row(source.output_column());
      if (source.Regressor(row, z)) {
        const double yhat = theta.dot(z);
        if (std::isfinite(y) && std::isfinite(yhat)) {
          y_meas.push_back(y);
          y_pred.push_back(yhat);
        }
        source.PushOutput(yhat);
      } else {
        source.PushOutput(r - segment.first < t0 ? y : std::nan(""));
      }
    }
    if (y_meas.size() >= 2) {
      double rms = 0;
      scores.simulation = fit(y_meas, y_pred, rms);
      scores.rms_simulation = rms;
    }
  }
  return scores;
}

FitResult Fit(io::DataTable data, DataSource& source, AnyRegressionEstimator& estimator, const FitOptions& options) {
  const auto [estimation, validation] = PrepareData(data, source, options);
  if (options.trace) WriteTraceHeader(options.trace, source.num_parameters());
  FitResult result;
  std::tie(result.updates, result.rejected) =
      Estimate(data, estimation, source, estimator, options.trace, options.decision, options.on_update);
  result.cleaned = source.cleaned();
  result.estimator = estimator.name();
  result.structure = source.structure();
  result.parameter_names = source.parameter_names();
  result.theta = estimator.parameters();
  result.theta_std = estimator.covariance().diagonal().cwiseMax(0).cwiseSqrt();
  result.noise_std = estimator.noise_std();
  result.nu = estimator.nu();
  result.Dy = estimator.Dy();
  result.samples_estimation = estimation.count;
  result.samples_validation = validation.count;
  result.validation = Score(data, validation, source, result.theta);
  return result;
}

}  // namespace ident::tools
