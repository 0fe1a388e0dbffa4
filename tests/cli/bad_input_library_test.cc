// The library side of the bad-input table: every constructor/option check throws
// ident::InvalidArgument whose message names the argument (readers throw ident::DataError naming
// the file, line and column).
#include <cmath>
#include <limits>
#include <string>

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <Eigen/Core>

#include "common/error.h"
#include "ident/density/logconcave_mle.h"
#include "ident/io/csv.h"
#include "ident/linalg/ld_factor.h"
#include "ident/observers/grid_observer.h"
#include "ident/observers/kalman_filter.h"
#include "ident/observers/lc_gaussian_filter.h"
#include "ident/registry/estimator_registry.h"
#include "ident/regression/regression_prior.h"
#include "ident/regression/rls.h"
#include "ident/regression/safe_student_regression.h"
#include "ident/regression/student_regression.h"
#include "ident/smoothing/map_smoother.h"
#include "ident/workflow/data_source.h"
#include "ident/workflow/fit.h"
#include "models/arx.h"
#include "models/measurement.h"
#include "models/penalties.h"
#include "models/state_space.h"
#include "tests/support/cli.h"

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

#define EXPECT_INVALID(statement, needle)                                         \
  do {                                                                            \
    const std::string message = InvalidArgumentMessage([&] { statement; });       \
    EXPECT_NE(message.find(needle), std::string::npos) << "message: " << message; \
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
  EXPECT_INVALID(RegressionPrior::FromGuess(Eigen::Vector2d(1, 2), Eigen::Matrix2d::Identity(), -1, 10, 1),
                 "sigma0 = -1");
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
  auto source = workflow::MakeArxSource(table.names, "y", {"u"}, arx, "<t>");
  auto estimator = MakeRegressionEstimator({}, source->num_parameters());
  workflow::FitOptions options;
  options.split = 1.5;
  EXPECT_INVALID(workflow::Fit(table, *source, *estimator, options), "split = 1.5; need 0 < split <= 1");
  options.split = 0.5;
  EXPECT_INVALID(workflow::Fit(table, *source, *estimator, options), "<t>: the estimation part has 3 rows");
  EXPECT_INVALID(workflow::MakeArxSource(table.names, "y", {"y"}, arx, "<t>"),
                 "column 'y' is both the output and an input");
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
    auto s1 = workflow::MakeArxSource(io::CsvReader(path).names(), "y", {"u"}, arx, path);
    auto s2 = s1->Clone();
    auto e1 = MakeRegressionEstimator({}, 4), e2 = MakeRegressionEstimator({}, 4);
    workflow::FitOptions options;
    options.split = split;
    const workflow::FitResult a = workflow::Fit(io::ReadCsv(path), *s1, *e1, options);
    const workflow::FitResult b = workflow::FitCsvFile(path, {}, *s2, *e2, options);
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
  const std::string dir = ident::testing::TempDir();
  const std::string path = dir + "/count.csv";
  {
    std::FILE* f = std::fopen(path.c_str(), "w");
    std::fputs("\n  \n\xEF\xBB\xBFu,y\r\n\n \t\r\n1,2\r\n3,4\r5,6\n7,8\r\n9,10",
               f);  // blank lines, CRLF, CR, no final newline
    std::fclose(f);
  }
  EXPECT_EQ(workflow::CountCsvDataRows(path), 5);
  const io::DataTable table = io::ReadCsv(path);
  ASSERT_EQ(table.num_rows(), 5);
  EXPECT_EQ(table.values(4, 1), 10);
}

// Comments and a missing header do not shift the streamed fit's rows: on the dryer record rewritten
// headerless, ';'-separated, with comment lines, the streamed fit equals the in-memory one.
TEST(StreamingFit, CommentsAndHeaderlessFilesCountLikeTheReader) {
  const io::DataTable dryer = io::ReadCsv("datasets/dryer.csv");
  std::string text = "# dryer, columns t;u;y\n";
  for (int i = 0; i < dryer.num_rows(); ++i) {
    text += fmt::format("{:.17g};{:.17g};{:.17g}\n", dryer.values(i, 0), dryer.values(i, 1), dryer.values(i, 2));
    if (i % 100 == 7) text += "  # a comment\n";
  }
  const std::string path = ident::testing::TempDir() + "/dryer_headerless.dat";
  {
    std::FILE* f = std::fopen(path.c_str(), "w");
    ASSERT_NE(f, nullptr);
    std::fputs(text.c_str(), f);
    std::fclose(f);
  }
  EXPECT_EQ(workflow::CountCsvDataRows(path) + 1, dryer.num_rows());  // the first row counted as a header
  const models::ArxStructure arx(2, {2}, {3});
  auto s1 = workflow::MakeArxSource(io::CsvReader(path).names(), "c3", {"c2"}, arx, path);
  auto s2 = s1->Clone();
  auto e1 = MakeRegressionEstimator({}, 4), e2 = MakeRegressionEstimator({}, 4);
  const workflow::FitResult a = workflow::Fit(io::ReadCsv(path), *s1, *e1, {});
  const workflow::FitResult b = workflow::FitCsvFile(path, {}, *s2, *e2, {});
  EXPECT_EQ(a.samples_estimation, 500);
  EXPECT_EQ(a.theta, b.theta);
  EXPECT_EQ(a.samples_estimation, b.samples_estimation);
  EXPECT_EQ(a.samples_validation, b.samples_validation);
}

// The record's length is checked from the row count before anything of the model's size is built;
// a bad row is still reported first.
TEST(BadInputLibrary, RecordLengthIsCheckedFromTheRowCountAlone) {
  const std::string dir = ident::testing::TempDir();
  auto write = [&](const std::string& name, const std::string& text) {
    const std::string path = dir + "/" + name;
    std::FILE* f = std::fopen(path.c_str(), "w");
    std::fputs(text.c_str(), f);
    std::fclose(f);
    return path;
  };
  const std::string path = write("short.csv", "u,y\n1,2\n2,3\n3,5\n4,4\n5,1\n6,0\n");
  auto source = workflow::MakeArxSource({"u", "y"}, "y", {"u"}, models::ArxStructure(2000, {2}, {1}), path);
  workflow::FitOptions options;
  EXPECT_INVALID(workflow::CheckCsvRecordLength(path, {}, *source, options),
                 "the estimation part has 3 rows; ARX(2000,2,1) with 2002 parameters needs at least 4003");
  auto small = workflow::MakeArxSource({"u", "y"}, "y", {"u"}, models::ArxStructure(1, {1}, {1}), path);
  EXPECT_INVALID(workflow::CheckCsvRecordLength(path, {}, *small, options),
                 "the estimation part has 3 rows; ARX(1,1,1) with 2 parameters needs at least 4");
  options.split = 1;  // 6 rows
  EXPECT_NO_THROW(workflow::CheckCsvRecordLength(path, {}, *small, options));
  options.split = 0.1;  // 0 estimation rows
  EXPECT_INVALID(workflow::CheckCsvRecordLength(path, {}, *small, options), "the estimation part has 0 rows");
  const std::string ragged = write("short_ragged.csv", "u,y\n1,2\n2,3,4\n");
  try {
    workflow::CheckCsvRecordLength(ragged, {}, *source, {});
    ADD_FAILURE() << "no error";
  } catch (const DataError& e) {
    EXPECT_NE(std::string(e.what()).find("short_ragged.csv:3: row has 3 fields; the header has 2"), std::string::npos)
        << e.what();
  }
}

TEST(BadInputLibrary, LockInWindowIsBounded) {
  EstimatorSettings s;
  s.name = "cauchy";
  s.lock_in.window = std::numeric_limits<int>::max();
  EXPECT_INVALID(MakeRegressionEstimator(s, 4), "lock_in_window = 2147483647; need 0 (automatic) or 2..1000000");
  s.lock_in.window = kMaxLockInWindow + 1;
  EXPECT_INVALID(MakeRegressionEstimator(s, 4), "lock_in_window = 1000001");
  s.lock_in.window = 1;
  EXPECT_INVALID(MakeRegressionEstimator(s, 4), "lock_in_window = 1;");
  s.lock_in.window = kMaxLockInWindow;
  const auto estimator = MakeRegressionEstimator(s, 4);
  ASSERT_TRUE(estimator->lock_in().has_value());
  EXPECT_EQ(estimator->lock_in()->window, 1000000);
}

TEST(BadInputLibrary, DeltaIsRefusedByTheEstimatorsWithoutTheConvention) {
  EstimatorSettings s;
  s.delta = 0;
  EXPECT_INVALID(MakeRegressionEstimator(s, 3), "delta = 0 does not apply to estimator 'rls'");
  s.name = "huber";
  EXPECT_INVALID(MakeRegressionEstimator(s, 3), "delta = 0 does not apply to estimator 'huber'");
  s.name = "cauchy";
  EXPECT_NO_THROW(MakeRegressionEstimator(s, 3));
  s.name = "student";
  s.dof = 3.0;
  EXPECT_NO_THROW(MakeRegressionEstimator(s, 3));
}

// nu_hard >= (k+3-delta)/k: a tiny k is blamed on k, with the bound it must exceed.
TEST(BadInputLibrary, TooSmallDofIsNamed) {
  EstimatorSettings s;
  s.name = "student";
  s.dof = 1e-300;
  EXPECT_INVALID(MakeRegressionEstimator(s, 4),
                 "dof = 1e-300 is too small: nu_hard >= (k+3-delta)/k = 2e+300 exceeds the first step's nu(1) = 6 "
                 "(nu0 = 5, delta = 1); need k > 0.4");
  s.dof = 0.3;  // nu0 = 5.3, nu(1) = 6.3 <= (0.3 + 2)/0.3 = 7.67
  EXPECT_INVALID(MakeRegressionEstimator(s, 4), "dof = 0.3 is too small");
  s.dof = 0.5;  // nu(1) = 6.5 > (0.5 + 2)/0.5 = 5
  EXPECT_NO_THROW(MakeRegressionEstimator(s, 4));
}

// ---- the libraries behind smooth, logcondens, mems and the Student/Cauchy estimators --------------

// A valid MAP smoothing problem: n = 2, nz = 1, T = 3.
MapSmootherProblem SmoothProblem() {
  MapSmootherProblem p;
  p.F = {(Eigen::MatrixXd(2, 2) << 1, 1, 0, 1).finished()};
  p.H = {(Eigen::MatrixXd(1, 2) << 1, 0).finished()};
  p.z = (Eigen::MatrixXd(1, 4) << 0.5, 1.2, 3.1, 2.0).finished();
  p.process = {models::Penalty::Quadratic(Eigen::MatrixXd::Identity(2, 2))};
  p.measurement = {models::Penalty::L1(1)};
  return p;
}

TEST(BadInputLibrary, MapSmootherProblemDimensionsAreCheckedByName) {
  EXPECT_NO_THROW(ValidateMapSmootherProblem(SmoothProblem()));
  MapSmootherProblem p = SmoothProblem();
  p.F = {Eigen::MatrixXd::Identity(3, 3)};
  EXPECT_INVALID(ValidateMapSmootherProblem(p), "F[0] is 3x3; need 2x2");
  p = SmoothProblem();
  p.F = {Eigen::MatrixXd::Identity(2, 2), Eigen::MatrixXd::Identity(2, 2)};  // T = 3 needs 1 or 3
  EXPECT_INVALID(ValidateMapSmootherProblem(p), "F has 2 matrices; need 1 or T = 3");
  p = SmoothProblem();
  p.H = {Eigen::MatrixXd::Ones(2, 2)};  // z has 1 row
  EXPECT_INVALID(ValidateMapSmootherProblem(p), "H[0] is 2x2; need 1x2");
  p = SmoothProblem();
  p.process = {models::Penalty::L1(3)};
  EXPECT_INVALID(ValidateMapSmootherProblem(p), "process penalty 0 has dimension 3; the state has 2");
  p = SmoothProblem();
  p.measurement = {models::Penalty::L1(2)};
  EXPECT_INVALID(ValidateMapSmootherProblem(p), "measurement penalty 0 has dimension 2; z has 1 rows");
  p = SmoothProblem();
  p.z(0, 2) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_INVALID(ValidateMapSmootherProblem(p), "z has a non-finite entry");
  p = SmoothProblem();
  p.z.resize(1, 0);
  EXPECT_INVALID(ValidateMapSmootherProblem(p), "z has no time steps");
  p = SmoothProblem();
  p.F[0](0, 1) = std::numeric_limits<double>::infinity();
  EXPECT_INVALID(ValidateMapSmootherProblem(p), "F[0] has a non-finite entry");
  EXPECT_INVALID(SolveMapSmoother(p), "F[0] has a non-finite entry");  // the solver checks too
}

TEST(BadInputLibrary, PenaltyParametersAreCheckedByName) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_INVALID(models::Penalty::Huber(0), "huber kappa = 0; need kappa > 0");
  EXPECT_INVALID(models::Penalty::Huber(-1), "huber kappa = -1");
  EXPECT_INVALID(models::Penalty::Huber(nan), "huber kappa = nan");
  EXPECT_INVALID(models::Penalty::Vapnik(-0.5), "vapnik epsilon = -0.5; need epsilon >= 0");
  EXPECT_INVALID(models::Penalty::Quantile(0), "quantile tau = 0; need 0 < tau < 1");
  EXPECT_INVALID(models::Penalty::Quantile(1), "quantile tau = 1");
  EXPECT_INVALID(models::Penalty::L1(0), "penalty dimension = 0; need >= 1");
  EXPECT_INVALID(models::Penalty::Quadratic(-Eigen::MatrixXd::Identity(1, 1)), "covariance is not positive definite");
  EXPECT_INVALID(models::Penalty::Quadratic((Eigen::MatrixXd(2, 2) << 1, 2, 0, 1).finished()), "covariance");
  EXPECT_INVALID(models::Penalty::Quadratic(Eigen::MatrixXd::Identity(2, 3)), "covariance is 2x3");
  EXPECT_INVALID(models::Penalty::PiecewiseLinear(Eigen::Vector2d(1, 0), Eigen::Vector2d(0, 0)),
                 "piecewise_linear knots must increase strictly");
  EXPECT_INVALID(models::Penalty::PiecewiseLinear(Eigen::Vector3d(0, 1, 2), Eigen::Vector2d(0, 0)),
                 "piecewise_linear has 3 knots but 2 values");
  EXPECT_INVALID(models::Penalty::PiecewiseLinear(Eigen::Vector3d(-1, 0, 1), Eigen::Vector3d(0, 1, 0)),
                 "piecewise_linear");  // not convex
  EXPECT_INVALID(models::Penalty::BoxMonitoring(Eigen::VectorXd::Constant(1, 1), Eigen::VectorXd::Constant(1, -1),
                                                Eigen::MatrixXd::Identity(1, 1)),
                 "box");
  EXPECT_INVALID(models::Penalty::BoxMonitoring(Eigen::VectorXd::Zero(2), Eigen::VectorXd::Ones(2),
                                                Eigen::MatrixXd::Identity(1, 1)),
                 "M is 1x1; need 2x2");
}

TEST(BadInputLibrary, LogConcaveMleInputsAreChecked) {
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  EXPECT_INVALID(approx::FitLogConcaveMle({}), "at least 2 distinct sample values, got 0");
  EXPECT_INVALID(approx::FitLogConcaveMle({2.0}), "at least 2 distinct sample values, got 1");
  EXPECT_INVALID(approx::FitLogConcaveMle({2.0, 2.0, 2.0}), "at least 2 distinct sample values, got 1");
  EXPECT_INVALID(approx::FitLogConcaveMle({1.0, nan, 2.0}), "sample 1 = nan is not finite");
  EXPECT_INVALID(approx::FitLogConcaveMle({1.0, 2.0, -inf}), "sample 2 = -inf is not finite");
  EXPECT_INVALID(approx::FitLogConcaveMle({-1.7e308, 0.0, 1.7e308}), "samples");  // range beyond double
  approx::LogConcaveMleOptions o;
  o.max_iterations = 0;
  EXPECT_INVALID(approx::FitLogConcaveMle({1.0, 2.0}, o), "max_iterations = 0");
  o = {};
  o.tolerance = 0;
  EXPECT_INVALID(approx::FitLogConcaveMle({1.0, 2.0}, o), "tolerance = 0");
}

TEST(BadInputLibrary, ObserverModelsAreCheckedByName) {
  const Eigen::Vector2d m0(0, 0);
  const Eigen::Matrix2d P0 = Eigen::Matrix2d::Identity();
  EXPECT_INVALID(KalmanFilter(m0, -P0), "P0 is not positive definite");
  EXPECT_INVALID(KalmanFilter(m0, Eigen::Matrix3d::Identity()), "P0 is 3×3");
  EXPECT_INVALID(LcGaussianFilter(Eigen::Vector2d(0, std::numeric_limits<double>::quiet_NaN()), P0), "m0");
  EXPECT_INVALID(GridObserver(m0, -P0), "P0 is not positive definite");
  EXPECT_INVALID(models::LinearStateSpace::Make(Eigen::MatrixXd::Identity(2, 3), Eigen::MatrixXd::Zero(2, 0),
                                                Eigen::MatrixXd::Identity(2, 2)),
                 "A is 2×3");
  EXPECT_INVALID(models::LinearStateSpace::Make(Eigen::MatrixXd::Identity(2, 2), Eigen::MatrixXd::Zero(2, 0),
                                                -Eigen::MatrixXd::Identity(2, 2)),
                 "process_noise");
  EXPECT_INVALID(models::MemsAccelerometerDynamics(0, 1), "sampling period h = 0");
  EXPECT_INVALID(models::MemsAccelerometerDynamics(0.01, -1), "noise intensity sigma^2 = -1");
  EXPECT_INVALID(models::GaussianMeasurement(Eigen::Vector2d(1, 0), -1), "noise_variance = -1");
  EXPECT_INVALID(models::ThresholdSensor(Eigen::Vector2d(1, 0), 0), "threshold = 0");
  EXPECT_INVALID(models::UniformQuantizer(Eigen::Vector2d(1, 0), -0.1), "quantizer step = -0.1");
  EXPECT_INVALID(models::GaussianMeasurement(Eigen::Vector2d(0, 0), 1), "c");
  // A model of the wrong size for the filter.
  const models::LinearStateSpace three = models::LinearStateSpace::Make(
      Eigen::MatrixXd::Identity(3, 3), Eigen::MatrixXd::Zero(3, 0), Eigen::MatrixXd::Identity(3, 3));
  EXPECT_INVALID(KalmanFilter(three, models::GaussianMeasurement(Eigen::Vector3d(1, 0, 0), 1), m0, P0), "");
}

TEST(BadInputLibrary, StudentDofAndDeltaAreCheckedByName) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (const double dof : {0.0, -1.0, nan}) {
    StudentRegressionOptions o;
    o.dof = dof;
    EXPECT_INVALID(StudentRegression(3, o), "dof = ");
  }
  StudentRegressionOptions o;
  o.delta = 2;
  EXPECT_INVALID(StudentRegression(3, o), "delta = 2; need 0 or 1");
  o = {};
  o.forgetting.factor = 1.5;
  EXPECT_INVALID(StudentRegression(3, o), "forgetting = 1.5");
  EXPECT_INVALID(StudentRegression(0), "number of parameters = 0");
  EstimatorSettings s;
  s.name = "student";
  s.dof = 0.0;
  EXPECT_INVALID(MakeRegressionEstimator(s, 3), "dof = 0");
  s.dof = -2.0;
  EXPECT_INVALID(MakeRegressionEstimator(s, 3), "dof = -2");
}

}  // namespace
}  // namespace ident
