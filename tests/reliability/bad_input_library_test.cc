// The library side of the bad-input table: every constructor/option check throws
// ident::InvalidArgument whose message names the argument (readers throw ident::DataError naming
// the file, line and column).
#include <cmath>
#include <limits>
#include <string>

#include <Eigen/Core>
#include <gtest/gtest.h>

#include "ident/common/error.h"
#include "ident/estimator_registry.h"
#include "ident/io/csv.h"
#include "ident/ld_factor.h"
#include "ident/regression_prior.h"
#include "ident/rls.h"
#include "models/arx.h"
#include "tools/data_source.h"
#include "tools/fit.h"

namespace ident {
namespace {

// Runs `f`, expects InvalidArgument, returns its message.
template <class F>
std::string InvalidArgumentMessage(F&& f) {
  try {
    f();
  } catch (const InvalidArgument& e) {
    return e.what();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "threw another exception: " << e.what();
    return {};
  }
  ADD_FAILURE() << "did not throw";
  return {};
}

#define EXPECT_INVALID(statement, needle)                                            \
  do {                                                                               \
    const std::string message = InvalidArgumentMessage([&] { statement; });          \
    EXPECT_NE(message.find(needle), std::string::npos) << "message: " << message;   \
  } while (false)

TEST(BadInputLibrary, ForgettingOutsideZeroOneIsRejectedByName) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (const double lambda : {0.0, -0.5, 1.5, nan, std::numeric_limits<double>::infinity()}) {
    RlsOptions options;
    options.forgetting.factor = lambda;
    EXPECT_INVALID(RecursiveLeastSquares(3, options), "forgetting = ");
  }
  RecursiveLeastSquares rls(2);
  EXPECT_INVALID(rls.set_forgetting(0), "forgetting = 0; need 0 < forgetting <= 1");
  EXPECT_EQ(rls.options().forgetting.factor, 1.0);  // unchanged
}

TEST(BadInputLibrary, PriorDegreesAndVariancesMustBePositive) {
  EXPECT_INVALID(RegressionPrior::Diagonal(2, 0, 1, 1).Validate(), "nu0 = 0");
  EXPECT_INVALID(RegressionPrior::Diagonal(2, -3, 1, 1).Validate(), "nu0 = -3");
  EXPECT_INVALID(RegressionPrior::Diagonal(2, 5, -1, 1), "vy0 = -1");
  EXPECT_INVALID(RegressionPrior::Diagonal(2, 5, 1, -1e-3), "vz0 = -0.001");
  EXPECT_INVALID(RegressionPrior::FromGuess(Eigen::Vector2d(1, 2), Eigen::Matrix2d::Identity(), -1, 10, 1), "sigma0 = -1");
  EXPECT_INVALID(RegressionPrior::FromGuess(Eigen::Vector2d(1, 2), -Eigen::Matrix2d::Identity(), 1, 10, 1),
                 "prior covariance P0 is not positive definite");
}

TEST(BadInputLibrary, PriorMatrixMustBeSymmetricPositiveDefiniteOfTheModelsSize) {
  RegressionPrior prior;
  prior.nu0 = 5;
  prior.V0 = (Eigen::Matrix2d() << 1, 2, 2, 1).finished();
  EXPECT_INVALID(prior.Validate(), "not positive definite");
  prior.V0 = Eigen::Matrix3d::Identity();
  RlsOptions options;
  options.prior = prior;
  EXPECT_INVALID(RecursiveLeastSquares(4, options), "prior matrix V0 is 3x3; need 5x5 for 4 parameters");
  EXPECT_INVALID(LdFactor<>((Eigen::Matrix2d() << 1, 0.5, 0, 1).finished()), "matrix V is not symmetric");
  EXPECT_INVALID(LdFactor<>((Eigen::Matrix2d() << 1, NAN, NAN, 1).finished()), "matrix V has a non-finite entry");
}

TEST(BadInputLibrary, UnknownEstimatorAndMisappliedDof) {
  EXPECT_INVALID(MakeRegressionEstimator(ParseEstimatorSpec("nonesuch"), 2), "unknown estimator 'nonesuch'");
  EstimatorSettings s;
  s.dof = -1;
  EXPECT_INVALID(MakeRegressionEstimator(s, 2), "dof = -1");
  EXPECT_INVALID(RecursiveLeastSquares(0), "number of parameters = 0");
}

TEST(BadInputLibrary, ArxOrdersAreCheckedByName) {
  EXPECT_INVALID(models::ArxStructure(-1, {2}, {1}), "na = -1; need na >= 0");
  EXPECT_INVALID(models::ArxStructure(1, {-2}, {1}), "nb = -2");
  EXPECT_INVALID(models::ArxStructure(1, {2}, {-1}), "nk = -1");
  EXPECT_INVALID(models::ArxStructure(0, {0}, {0}), "the model has no parameters");
}

TEST(BadInputLibrary, FitWorkflowChecksSplitAndRecordLength) {
  io::DataTable table = io::ParseCsv("u,y\n1,2\n2,3\n3,5\n4,4\n5,1\n6,0\n", "<t>");
  const models::ArxStructure arx(1, {1}, {1});
  auto source = tools::MakeArxSource(table.names, "y", {"u"}, arx, "<t>");
  auto estimator = MakeRegressionEstimator({}, source->num_parameters());
  tools::FitOptions options;
  options.split = 1.5;
  EXPECT_INVALID(tools::Fit(table, *source, *estimator, options), "split = 1.5; need 0 < split <= 1");
  options.split = 0.5;
  EXPECT_INVALID(tools::Fit(table, *source, *estimator, options), "<t>: the estimation part has 3 rows");
  EXPECT_INVALID(tools::MakeArxSource(table.names, "y", {"y"}, arx, "<t>"), "column 'y' is both the output and an input");
}

TEST(BadInputLibrary, CsvTextErrorsAreDataErrorsNamingLineAndColumn) {
  auto message = [](const std::string& text) {
    try {
      io::ParseCsv(text, "<text>");
    } catch (const DataError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(message(""), "<text>: the file is empty");
  EXPECT_EQ(message("a,b\n"), "<text>: no data rows after the header");
  EXPECT_EQ(message("a,b\n1,2\n3\n"), "<text>:3: row has 1 field; the header has 2");
  EXPECT_EQ(message("a,b\n1,zz\n"), "<text>:2: column 2 ('b'): 'zz' is not a number");
  EXPECT_EQ(message("a,b\n1,1e999\n"), "<text>:2: column 2 ('b'): '1e999' is out of the range of double");
  EXPECT_EQ(message("a,a\n1,2\n"), "<text>:1: duplicate column name 'a' (columns 1 and 2)");
}

// The streamed fit and the in-memory fit are the same computation: equal θ and scores on a real record.
TEST(StreamingFit, EqualsTheInMemoryFitOnTheDryerRecord) {
  const std::string path = "datasets/dryer.csv";
  const models::ArxStructure arx(2, {2}, {3});
  for (const double split : {0.5, 1.0}) {
    auto s1 = tools::MakeArxSource(io::CsvReader(path).names(), "y", {"u"}, arx, path);
    auto s2 = s1->Clone();
    auto e1 = MakeRegressionEstimator({}, 4), e2 = MakeRegressionEstimator({}, 4);
    tools::FitOptions options;
    options.split = split;
    const tools::FitResult a = tools::Fit(io::ReadCsv(path), *s1, *e1, options);
    const tools::FitResult b = tools::FitCsvFile(path, {}, *s2, *e2, options);
    EXPECT_EQ(a.theta, b.theta) << split;  // same arithmetic, bit for bit
    EXPECT_EQ(a.updates, b.updates);
    EXPECT_EQ(a.samples_estimation, b.samples_estimation);
    EXPECT_EQ(a.samples_validation, b.samples_validation);
    EXPECT_EQ(a.validation.scored, b.validation.scored);
    EXPECT_DOUBLE_EQ(a.validation.one_step, b.validation.one_step);
    EXPECT_DOUBLE_EQ(*a.validation.simulation, *b.validation.simulation);
  }
}

TEST(StreamingFit, CountsDataRowsLikeTheReader) {
  const std::string dir = ::testing::TempDir();
  const std::string path = dir + "/count.csv";
  {
    std::FILE* f = std::fopen(path.c_str(), "w");
    std::fputs("\n  \n\xEF\xBB\xBFu,y\r\n1,2\r\n\n \t\r\n3,4\n5,6", f);  // blank lines, CRLF, no final newline
    std::fclose(f);
  }
  EXPECT_EQ(tools::CountCsvDataRows(path), 3);
  EXPECT_EQ(io::ReadCsv(path).num_rows(), 3);
}

}  // namespace
}  // namespace ident
