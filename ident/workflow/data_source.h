// Turning a recorded table into regression data items for a model structure (tool layer).
//
//   ArxSource      ARX/FIR (MISO) from an output column and input columns: z(t) as in models/arx.h;
//                  supports simulation (feeding back the model's own output).
//   PolynomialSource ARMAX/OE/BJ: the pseudo-linear regressor of models/pseudo_linear_regressor.h, which
//                  also needs the estimate (SetEstimate / TrackEstimate) to form its residuals.
//   StaticSource   static regression y = θ'x (+ intercept) from named columns.
//
// Both walk one segment of rows at a time: Reset() at the segment start (Restart() at each further
// experiment's first row), then per row Regressor(row, z) (true if a regression happens at this row)
// followed by PushOutput(y).
#pragma once

#include <cmath>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "ident/io/csv.h"
#include "models/arx.h"
#include "models/polynomial_structure.h"
#include "models/pseudo_linear_regressor.h"

namespace ident::workflow {

// Whether every entry of z is finite: Eigen's allFinite() as a plain loop, for the per-row paths (Eigen
// forms z − z twice and compares, out of line at dynamic size).
inline bool AllFinite(const Eigen::Ref<const Eigen::VectorXd>& z) {
  for (Eigen::Index i = 0; i < z.size(); ++i)
    if (!std::isfinite(z(i))) return false;
  return true;
}

class DataSource {
 public:
  virtual ~DataSource() = default;
  // An independent copy (same structure and columns, same walking state).
  virtual std::unique_ptr<DataSource> Clone() const = 0;
  virtual int num_parameters() const = 0;
  virtual std::string structure() const = 0;  // "ARX(2,2,3)", "static(x1,x2)+intercept"
  virtual std::vector<std::string> parameter_names() const = 0;
  virtual bool dynamic() const = 0;                // simulation applies
  virtual int first_regression_index() const = 0;  // t0 within a segment
  virtual int output_column() const = 0;
  virtual std::vector<int> used_columns() const = 0;  // every column the model reads
  virtual void Reset() = 0;
  // A further experiment starts (io::DataTable::experiment_starts): the regressor history restarts as at
  // Reset(), so the experiment's first t0 rows only fill it; the estimate and cleaned() carry on.
  virtual void Restart() { Reset(); }
  virtual bool Regressor(const Eigen::Ref<const Eigen::VectorXd>& row, Eigen::Ref<Eigen::VectorXd> z) = 0;
  virtual void PushOutput(double y) = 0;
  // True when Regressor() is affine in the rows, with no state beyond the last first_regression_index()
  // rows and the outputs pushed: shifting every row by a constant c shifts z by z(c) − z(0), the regressors
  // of constant rows c and 0 (ARX: lagged values; static: the columns and an intercept).
  virtual bool affine_in_rows() const { return false; }
  // During estimation: stores y, or (ARX with cleaning on) its cleaned value when the estimator
  // flagged the sample (models/output_cleaner.h); `judged` says whether the estimator gives verdicts at
  // all (AnyRegressionEstimator::judges_outliers). Returns the stored value.
  virtual double PushCheckedOutput(double y, double /*y_hat*/, double /*scale*/, bool /*flagged*/, bool /*judged*/) {
    PushOutput(y);
    return y;
  }
  virtual long cleaned() const { return 0; }  // samples cleaned since Reset()
  // Additive outlier or innovation (models/arx.h ArxRegressor::MeasuredRegressor): after Regressor(), if
  // the last output was cleaned, the regressor with the measured value instead, and a way to keep it.
  virtual bool MeasuredRegressor(Eigen::Ref<Eigen::VectorXd> /*z_measured*/) const { return false; }
  virtual void RestoreMeasured() {}
  // After Regressor() (and the choice above): the regressor holds an output stored cleaned, so its equation
  // has an error in a variable of the size of the prediction error (models/arx.h ArxRegressor::HoldsCleaned).
  virtual bool RegressorHoldsCleaned() const { return false; }
  // Whether a prediction error is gross for the output cleaner (models/arx.h ArxRegressor::IsGrossError).
  virtual bool IsGrossError(double /*e*/) const { return false; }
  // When the last output was cleaned by the model-free warm-up screen, that screen's answer to the same
  // question (models/arx.h ArxRegressor::MeasuredIsNearer); nullopt: the model's predictions decide.
  virtual std::optional<bool> MeasuredIsNearer(double /*y*/) const { return std::nullopt; }
  // The estimator has made its robust start: cleaning judges by its predictions from now on.
  virtual void EndCleaningWarmUp() {}
  // ARMAX/OE/BJ: the regressor holds the model's own past residuals and noise-free outputs, which depend
  // on θ. True for such a source; its walkers then tell it θ: SetEstimate(θ) once for a fixed model
  // (prediction, scoring), TrackEstimate(θ(t)) after each update of a recursive estimation (the stability
  // projection of models/pseudo_linear_regressor.h applies). Other sources ignore both.
  virtual bool uses_estimate() const { return false; }
  virtual void SetEstimate(const Eigen::Ref<const Eigen::VectorXd>& /*theta*/) {}
  // `start_up`: θ is a provisional one formed while a robust start-up collects its window: the measured
  // outputs stand in for the noise-free ones.
  virtual void TrackEstimate(const Eigen::Ref<const Eigen::VectorXd>& /*theta*/, bool /*start_up*/) {}
  // The output the estimator regresses on Regressor()'s z for the measured y: y itself, or the RPEM
  // source's linearised output (models/pseudo_linear_regressor.h).
  virtual double RegressionOutput(double y) const { return y; }
  // No estimate: the measured outputs stand in for the residuals and noise-free outputs.
  virtual void ClearEstimate() {}
  // Why the one-step predictor of the model θ is unstable — a C or F polynomial (ARMAX, OE, BJ) with a root
  // on or outside the unit circle, which the predictor divides by — or empty if it is stable (always for ARX
  // and static structures).
  virtual std::string UnstablePredictor(const Eigen::Ref<const Eigen::VectorXd>& /*theta*/) const { return {}; }
};

// Throws DataError for an unknown column, InvalidArgument for bad orders.
std::unique_ptr<DataSource> MakeArxSource(const std::vector<std::string>& columns, const std::string& output,
                                          const std::vector<std::string>& inputs, const models::ArxStructure& arx,
                                          const std::string& source,
                                          const models::OutputCleaningOptions& cleaning = {});
std::unique_ptr<DataSource> MakePolynomialSource(const std::vector<std::string>& columns, const std::string& output,
                                                 const std::vector<std::string>& inputs,
                                                 const models::PolynomialStructure& structure,
                                                 const std::string& source,
                                                 const models::OutputCleaningOptions& cleaning = {},
                                                 models::Recursion recursion = models::Recursion::kPseudoLinear);
std::unique_ptr<DataSource> MakeStaticSource(const std::vector<std::string>& columns, const std::string& output,
                                             const models::StaticRegression& regression, const std::string& source);

}  // namespace ident::workflow
