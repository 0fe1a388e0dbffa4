// A batch estimator in the recursive workflow: it solves all stored samples whenever a read-out follows
// new samples (ident/regression/batch_regression.h), so the estimation loop must not read it out per row.
// Counted with a decorator: read-outs that follow an update are solves.
#include <memory>

#include <gtest/gtest.h>

#include "ident/io/csv.h"
#include "ident/registry/estimator_registry.h"
#include "ident/workflow/data_source.h"
#include "ident/workflow/fit.h"
#include "models/polynomial_structure.h"
#include "tests/support/forwarding_estimator.h"
#include "tests/support/test_data.h"

namespace ident {
namespace {

class SolveCounter final : public testing::ForwardingEstimator {
 public:
  using ForwardingEstimator::ForwardingEstimator;
  StepReport Update(double y, const Eigen::Ref<const Eigen::VectorXd>& z) override {
    fresh_ = true;
    ++updates;
    return ForwardingEstimator::Update(y, z);
  }
  Eigen::VectorXd parameters() const override { return Read(), ForwardingEstimator::parameters(); }
  Eigen::MatrixXd covariance() const override { return Read(), ForwardingEstimator::covariance(); }
  double Predict(const Eigen::Ref<const Eigen::VectorXd>& z) const override {
    return Read(), ForwardingEstimator::Predict(z);
  }
  double Dy() const override { return Read(), ForwardingEstimator::Dy(); }
  double noise_std() const override { return Read(), ForwardingEstimator::noise_std(); }

  int updates = 0;
  mutable int solves = 0;

 private:
  void Read() const {
    solves += fresh_;
    fresh_ = false;
  }
  mutable bool fresh_ = false;
};

TEST(BatchEstimatorInTheWorkflow, IsSolvedOncePerFitNotOncePerRow) {
  const std::string path = testing::DatasetPath("dryer.csv");
  for (const char* name : {"cauchy-ml", "huber"}) {
    auto source = workflow::MakeArxSource(io::CsvReader(path).names(), "y", {"u"}, models::ArxStructure(2, {2}, {3}),
                                          path, {.enabled = true});
    EstimatorSettings settings;
    settings.name = name;
    SolveCounter estimator(MakeRegressionEstimator(settings, source->num_parameters()));
    ASSERT_EQ(estimator.kind(), "batch");
    const workflow::FitResult fit = workflow::Fit(io::ReadCsv(path), *source, estimator, {});
    EXPECT_EQ(estimator.updates, 496) << name;  // rows 4..500 of the estimation half
    EXPECT_LE(estimator.solves, 2) << name;
    EXPECT_GT(fit.validation.one_step, 90) << name;  // the fit itself is unchanged by how often it is read
  }
}

// ARMAX, whose regressors hold residuals of the current estimate: a batch estimator is read at geometrically
// spaced updates (10 % more samples each time), not at every row, which would be O(N²).
TEST(BatchEstimatorInTheWorkflow, ArmaxReadsTheBatchEstimateAtGeometricallySpacedUpdates) {
  const std::string path = testing::DatasetPath("dryer.csv");
  for (const char* name : {"cauchy-ml", "huber"}) {
    auto source = workflow::MakePolynomialSource(io::CsvReader(path).names(), "y", {"u"},
                                                 models::PolynomialStructure::Armax(2, {2}, 1, {3}), path);
    EstimatorSettings settings;
    settings.name = name;
    SolveCounter estimator(MakeRegressionEstimator(settings, source->num_parameters()));
    const workflow::FitResult fit = workflow::Fit(io::ReadCsv(path), *source, estimator, {});
    EXPECT_EQ(estimator.updates, 496) << name;
    // reads from update 20 on at 10 % steps: log(496 / 20) / log(1.1) ≈ 34, plus the result's
    EXPECT_LE(estimator.solves, 40) << name;
    EXPECT_GE(estimator.solves, 30) << name;
    EXPECT_GT(fit.validation.one_step, 94) << name;  // ARX's 93.8 % and the recursive ARMAX's 95.2 %
  }
}

}  // namespace
}  // namespace ident
