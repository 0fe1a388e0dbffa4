#include "ident/workflow/data_source.h"

#include <algorithm>
#include <tuple>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "common/error.h"
#include "models/pseudo_linear_regressor.h"

namespace ident::workflow {
namespace {

int Find(const std::vector<std::string>& columns, const std::string& name, const std::string& source) {
  for (std::size_t i = 0; i < columns.size(); ++i)
    if (columns[i] == name) return static_cast<int>(i);
  io::ThrowUnknownColumn(source, name, columns);
}

// What ARX and the polynomial structures share: an output column and input columns walked through a
// regressor of type R (models::ArxRegressor, models::PseudoLinearRegressor), which forms z(t) and keeps the
// outputs with their cleaning.
template <class R>
class DynamicSource : public DataSource {
 public:
  int num_parameters() const override { return regressor_.structure().num_parameters(); }
  std::string structure() const override { return regressor_.structure().ToString(); }
  std::vector<std::string> parameter_names() const override { return regressor_.structure().ParameterNames(); }
  bool dynamic() const override { return true; }
  int first_regression_index() const override { return regressor_.structure().first_regression_index(); }
  int output_column() const override { return output_; }
  std::vector<int> used_columns() const override {
    std::vector<int> used = inputs_;
    used.push_back(output_);
    return used;
  }
  void Reset() override {
    regressor_.Reset();
    cleaned_before_ = 0;
  }
  void Restart() override {
    cleaned_before_ += regressor_.cleaner().cleaned();
    regressor_.Reset();
  }
  bool Regressor(const Eigen::Ref<const Eigen::VectorXd>& row, Eigen::Ref<Eigen::VectorXd> z) override {
    for (std::size_t i = 0; i < inputs_.size(); ++i) u_(static_cast<Eigen::Index>(i)) = row(inputs_[i]);
    return regressor_.Next(u_, z);
  }
  void PushOutput(double y) override { regressor_.PushOutput(y); }
  double PushCheckedOutput(double y, double y_hat, double scale, bool flagged, bool judged) override {
    return regressor_.PushCheckedOutput(y, y_hat, scale, flagged, judged);
  }
  long cleaned() const override { return cleaned_before_ + regressor_.cleaner().cleaned(); }
  void EndCleaningWarmUp() override { regressor_.EndCleaningWarmUp(); }

 protected:
  DynamicSource(int output, std::vector<int> inputs, R regressor)
      : output_(output), inputs_(std::move(inputs)), regressor_(std::move(regressor)), u_(inputs_.size()) {}
  R& regressor() { return regressor_; }
  const R& regressor() const { return regressor_; }

 private:
  int output_;
  std::vector<int> inputs_;
  R regressor_;
  Eigen::VectorXd u_;
  long cleaned_before_ = 0;  // cleaned in the experiments before the current one
};

class ArxSource final : public DynamicSource<models::ArxRegressor> {
 public:
  ArxSource(int output, std::vector<int> inputs, const models::ArxStructure& arx,
            const models::OutputCleaningOptions& cleaning)
      : DynamicSource(output, std::move(inputs), models::ArxRegressor(arx, cleaning)) {}
  std::unique_ptr<DataSource> Clone() const override { return std::make_unique<ArxSource>(*this); }
  bool affine_in_rows() const override { return true; }
  bool MeasuredRegressor(Eigen::Ref<Eigen::VectorXd> z_measured) const override {
    return regressor().MeasuredRegressor(z_measured);
  }
  void RestoreMeasured() override { regressor().RestoreMeasured(); }
  bool RegressorHoldsCleaned() const override { return regressor().HoldsCleaned(); }
  bool IsGrossError(double e) const override { return regressor().IsGrossError(e); }
  std::optional<bool> MeasuredIsNearer(double y) const override { return regressor().MeasuredIsNearer(y); }
};

class PolynomialSource final : public DynamicSource<models::PseudoLinearRegressor> {
 public:
  PolynomialSource(int output, std::vector<int> inputs, const models::PolynomialStructure& structure,
                   const models::OutputCleaningOptions& cleaning, models::Recursion recursion)
      : DynamicSource(output, std::move(inputs), models::PseudoLinearRegressor(structure, cleaning, recursion)) {}
  std::unique_ptr<DataSource> Clone() const override { return std::make_unique<PolynomialSource>(*this); }
  bool uses_estimate() const override { return true; }
  void SetEstimate(const Eigen::Ref<const Eigen::VectorXd>& theta) override { regressor().SetEstimate(theta); }
  void TrackEstimate(const Eigen::Ref<const Eigen::VectorXd>& theta, bool start_up) override {
    regressor().TrackEstimate(theta, start_up);
  }
  void ClearEstimate() override { regressor().ClearEstimate(); }
  double RegressionOutput(double y) const override { return regressor().LinearisedOutput(y); }
  bool RegressorHoldsCleaned() const override { return regressor().HoldsCleaned(); }
  std::string UnstablePredictor(const Eigen::Ref<const Eigen::VectorXd>& theta) const override {
    const models::PolynomialStructure& s = regressor().structure();
    std::vector<double> work(static_cast<std::size_t>(std::max(s.nc(), s.nf())));
    const bool rpem = regressor().recursion() == models::Recursion::kPredictionError;
    for (const auto& [name, offset, n] :
         {std::tuple{'C', s.c_offset(), s.nc()}, std::tuple{'F', s.f_offset(), s.nf()}}) {
      if (n == 0 || models::MonicStable(theta.data() + offset, n, work.data())) continue;
      return fmt::format(
          "the estimated {0}(q) has a root of modulus {1:.4g}, on or outside the unit circle, so the one-step "
          "predictor, which divides by {0}(q), is unstable ({2})",
          name, models::LargestRootModulus(theta.data() + offset, n),
          rpem ? "try lower orders or another estimator" : "--recursion rpem keeps C and F stable while estimating");
    }
    return {};
  }
};

class StaticSource final : public DataSource {
 public:
  StaticSource(int output, std::vector<int> regressors, models::StaticRegression regression)
      : output_(output), columns_(std::move(regressors)), regression_(std::move(regression)) {
    IDENT_REQUIRE(columns_.size() == regression_.regressors.size(), "{} regressor columns for {} regressors",
                  columns_.size(), regression_.regressors.size());
  }
  std::unique_ptr<DataSource> Clone() const override { return std::make_unique<StaticSource>(*this); }
  bool affine_in_rows() const override { return true; }
  int num_parameters() const override { return regression_.num_parameters(); }
  std::string structure() const override {
    return fmt::format("static({}){}", fmt::join(regression_.regressors, ","),
                       regression_.intercept ? "+intercept" : "");
  }
  std::vector<std::string> parameter_names() const override { return regression_.ParameterNames(); }
  bool dynamic() const override { return false; }
  int first_regression_index() const override { return 0; }
  int output_column() const override { return output_; }
  std::vector<int> used_columns() const override {
    std::vector<int> used = columns_;
    used.push_back(output_);
    return used;
  }
  void Reset() override {}
  // z = (1, x) or x as models::StaticRegression::Regressor builds it, written in place: this runs once per
  // row in every pass over a record.
  bool Regressor(const Eigen::Ref<const Eigen::VectorXd>& row, Eigen::Ref<Eigen::VectorXd> z) override {
    const int offset = regression_.intercept ? 1 : 0;
    if (offset) z(0) = 1.0;
    for (std::size_t i = 0; i < columns_.size(); ++i) z(offset + static_cast<Eigen::Index>(i)) = row(columns_[i]);
    return true;
  }
  void PushOutput(double) override {}

 private:
  int output_;
  std::vector<int> columns_;
  models::StaticRegression regression_;
};

}  // namespace

std::unique_ptr<DataSource> MakeArxSource(const std::vector<std::string>& columns, const std::string& output,
                                          const std::vector<std::string>& inputs, const models::ArxStructure& arx,
                                          const std::string& source, const models::OutputCleaningOptions& cleaning) {
  IDENT_REQUIRE(static_cast<int>(inputs.size()) == arx.num_inputs(),
                "{} input column(s) given but the orders describe {} input(s)", inputs.size(), arx.num_inputs());
  std::vector<int> in;
  for (const auto& name : inputs) {
    IDENT_REQUIRE(name != output, "column '{}' is both the output and an input", name);
    in.push_back(Find(columns, name, source));
  }
  return std::make_unique<ArxSource>(Find(columns, output, source), std::move(in), arx, cleaning);
}

std::unique_ptr<DataSource> MakePolynomialSource(const std::vector<std::string>& columns, const std::string& output,
                                                 const std::vector<std::string>& inputs,
                                                 const models::PolynomialStructure& structure,
                                                 const std::string& source,
                                                 const models::OutputCleaningOptions& cleaning,
                                                 models::Recursion recursion) {
  IDENT_REQUIRE(static_cast<int>(inputs.size()) == structure.num_inputs(),
                "{} input column(s) given but the orders describe {} input(s)", inputs.size(), structure.num_inputs());
  std::vector<int> in;
  for (const auto& name : inputs) {
    IDENT_REQUIRE(name != output, "column '{}' is both the output and an input", name);
    in.push_back(Find(columns, name, source));
  }
  return std::make_unique<PolynomialSource>(Find(columns, output, source), std::move(in), structure, cleaning,
                                            recursion);
}

std::unique_ptr<DataSource> MakeStaticSource(const std::vector<std::string>& columns, const std::string& output,
                                             const models::StaticRegression& regression, const std::string& source) {
  IDENT_REQUIRE(regression.num_parameters() >= 1, "static regression needs at least one regressor or --intercept");
  std::vector<int> x;
  for (const auto& name : regression.regressors) {
    IDENT_REQUIRE(name != output, "column '{}' is both the output and a regressor", name);
    x.push_back(Find(columns, name, source));
  }
  return std::make_unique<StaticSource>(Find(columns, output, source), std::move(x), regression);
}

}  // namespace ident::workflow
