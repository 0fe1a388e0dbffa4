// A result is reported only if it is usable: θ, its standard errors and the noise scale finite, and at
// least ρ + 1 accepted updates. Otherwise one line says why and the exit code is 1. Also: the same model
// from data in other units (every estimator), a library Predict that checks its argument, compare
// reporting one estimator's failure beside the others, and the MEMS study refusing a run without events.
#include <cmath>
#include <string>

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "common/error.h"
#include "ident/io/csv.h"
#include "ident/registry/estimator_registry.h"
#include "ident/regression/batch_regression.h"
#include "ident/regression/rls.h"
#include "ident/regression/safe_student_regression.h"
#include "ident/regression/student_regression.h"
#include "ident/workflow/compare.h"
#include "ident/workflow/data_source.h"
#include "ident/workflow/fit.h"
#include "models/polynomial_structure.h"
#include "tests/cli/scaled_dryer.h"
#include "tests/support/cli.h"
#include "tests/support/forwarding_estimator.h"
#include "tests/support/test_data.h"

namespace ident::testing {
namespace {

const std::string kUsableArx = " --output y --input u --na 2 --nb 2 --nk 3";

nlohmann::json UsableFitJson(const std::string& args) {
  const CliResult r = RunCli(args + " --json");
  EXPECT_EQ(r.exit_code, 0) << args << ": " << r.err;
  return r.exit_code == 0 ? nlohmann::json::parse(r.out) : nlohmann::json();
}

// The roots of the monic polynomials below are known in closed form: 1 − 1.5 q⁻¹ has its root at 1.5,
// 1 − 2.5 q⁻¹ + q⁻² at 2 and 0.5, 1 + 0.36 q⁻² at ±0.6i.
TEST(UsableResult, LargestRootModulusOfKnownPolynomials) {
  const double c[] = {-1.5}, f[] = {-2.5, 1.0}, g[] = {0.0, 0.36};
  EXPECT_NEAR(models::LargestRootModulus(c, 1), 1.5, 1e-12);
  EXPECT_NEAR(models::LargestRootModulus(f, 2), 2.0, 1e-12);
  EXPECT_NEAR(models::LargestRootModulus(g, 2), 0.6, 1e-12);
  EXPECT_EQ(models::LargestRootModulus(c, 0), 0.0);
}

// A model whose one-step predictor divides by an unstable C or F has no predictions: the source names the
// polynomial and its largest root; a stable one, and ARX, pass.
TEST(UsableResult, UnstablePredictorNamesThePolynomialAndItsRoot) {
  const std::vector<std::string> columns = {"u", "y"};
  auto armax =
      workflow::MakePolynomialSource(columns, "y", {"u"}, models::PolynomialStructure::Armax(1, {1}, 1, {1}), "test");
  EXPECT_EQ(armax->parameter_names(), (std::vector<std::string>{"a1", "b1", "c1"}));
  EXPECT_EQ(armax->UnstablePredictor(Eigen::Vector3d(-0.5, 1.0, -0.5)), "");
  EXPECT_NE(armax->UnstablePredictor(Eigen::Vector3d(-0.5, 1.0, -1.5)).find("C(q) has a root of modulus 1.5,"),
            std::string::npos);
  auto oe =
      workflow::MakePolynomialSource(columns, "y", {"u"}, models::PolynomialStructure::OutputError(1, 2, 1), "test");
  EXPECT_NE(oe->UnstablePredictor(Eigen::Vector3d(1.0, -2.5, 1.0)).find("F(q) has a root of modulus 2,"),
            std::string::npos);
  EXPECT_EQ(oe->UnstablePredictor(Eigen::Vector3d(1.0, 0.0, 0.36)), "");
  auto arx = workflow::MakeArxSource(columns, "y", {"u"}, models::ArxStructure(1, {1}, {1}), "test");
  EXPECT_EQ(arx->UnstablePredictor(Eigen::Vector2d(-5.0, 1.0)), "");
}

// The workflow refuses such a model instead of reporting undefined predictions: an estimator whose estimate
// is read with C(q) = 1 − 1.5 q⁻¹.
class UnstableCEstimate final : public ForwardingEstimator {
 public:
  using ForwardingEstimator::ForwardingEstimator;
  Eigen::VectorXd parameters() const override {
    Eigen::VectorXd theta = ForwardingEstimator::parameters();
    theta(theta.size() - 1) = -1.5;
    return theta;
  }
};

TEST(UsableResult, AModelWithAnUnstablePredictorIsRefused) {
  const std::string path = DatasetPath("dryer.csv");
  auto source = workflow::MakePolynomialSource(io::CsvReader(path).names(), "y", {"u"},
                                               models::PolynomialStructure::Armax(2, {2}, 1, {3}), path);
  UnstableCEstimate estimator(MakeRegressionEstimator(ParseEstimatorSpec("rls"), source->num_parameters()));
  try {
    workflow::Fit(io::ReadCsv(path), *source, estimator, {});
    ADD_FAILURE() << "no error";
  } catch (const DataError& e) {
    EXPECT_NE(std::string(e.what()).find("the result is unusable: the estimated C(q) has a root of modulus 1.5"),
              std::string::npos)
        << e.what();
  }
}

// Forgetting 0.5 keeps about two samples of information for four parameters: the noise std is not
// defined (NaN), and the standard errors with it.
TEST(UsableResult, ForgettingFarBelowOneIsRefusedInsteadOfNanStandardErrors) {
  ExpectCliError("fit dryer" + kUsableArx + " --forgetting 0.5",
                 "the result is unusable: the noise std is nan: the estimate rests on the information of nu = 2");
  ExpectCliError("fit dryer" + kUsableArx + " --forgetting 0.5 --json", "raise --forgetting");
}

// u × 1e-100 and y × 1e100: the b parameters are near 1e198 and their variances near 1e396, beyond double.
TEST(UsableResult, ColumnsOfFarApartScalesAreRefusedInsteadOfInfiniteStandardErrors) {
  const std::string path = ScaledDryer("dryer_mixed.csv", 1e-100, 1e100);
  ExpectCliError("fit " + path + kUsableArx, "the standard error of parameter 'b1'");
  ExpectCliError("fit " + path + kUsableArx + " --json",
                 "its variance is infinite (columns whose scales are too far apart");
}

// ARX θ does not change when u and y are scaled alike: every estimator, recursive and batch, returns the
// unscaled record's θ from dryer × 1e-90 (squares near 1e-180, ordinary doubles).
TEST(UsableResult, EveryEstimatorGivesTheSameModelFromDataInTinyUnits) {
  const std::string tiny = ScaledDryer("dryer_em90.csv", 1e-90);
  for (const std::string estimator : {"rls", "cauchy", "student:3", "huber", "cauchy-ml"}) {
    const auto base = UsableFitJson("fit dryer" + kUsableArx + " --estimator " + estimator);
    const auto scaled = UsableFitJson("fit " + tiny + kUsableArx + " --estimator " + estimator);
    if (base.is_null() || scaled.is_null()) continue;
    for (int i = 0; i < 4; ++i)
      EXPECT_NEAR(scaled["theta"][i].get<double>(), base["theta"][i].get<double>(), 1e-7)
          << estimator << " theta " << i;
    EXPECT_NEAR(scaled["fit_percent"]["one_step"].get<double>(), base["fit_percent"]["one_step"].get<double>(), 1e-6)
        << estimator;
    EXPECT_NEAR(scaled["noise_std"].get<double>() / 1e-90, base["noise_std"].get<double>(),
                1e-7 * base["noise_std"].get<double>())
        << estimator;
  }
}

// Student-t with k = 1e80 degrees of freedom is the Gaussian model: every sample is used and θ is the
// least-squares one (up to the different start-up prior), not θ = 0 after refusing most of the record.
TEST(UsableResult, StudentWithHugeDegreesOfFreedomBehavesAsLeastSquares) {
  const auto rls = UsableFitJson("fit dryer" + kUsableArx + " --estimator rls");
  const auto student = UsableFitJson("fit dryer" + kUsableArx + " --estimator student --dof 1e80");
  if (rls.is_null() || student.is_null()) return;
  EXPECT_EQ(student["updates"].get<int>(), rls["updates"].get<int>());
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(student["theta"][i].get<double>(), rls["theta"][i].get<double>(), 1e-2) << i;
}

// A record and the same record in other units by a power of two give the same fit, bit for bit, outlier
// cleaning included: the cleaning before the robust start judges by a provisional estimate whose prior is
// in the data's units (UseDataScaledPrior). With that prior in absolute units, exchanger with 5 % outliers
// of 20 σ gave θ 45 % apart in the two units.
TEST(UsableResult, TheFitDoesNotDependOnTheUnitsOfTheData) {
  io::DataTable table = io::ReadCsv(DatasetPath("exchanger.csv"));
  ASSERT_EQ(table.names[2], "y");
  Eigen::VectorXd y = table.values.col(2);
  workflow::InjectOutliers(y, {0, static_cast<int>(table.num_rows() / 2)}, 0.05, 20 * 0.334, 3);
  table.values.col(2) = y;
  const auto write = [&](const std::string& name, int k) {
    std::string text = "t,u,y\n";
    for (Eigen::Index i = 0; i < table.values.rows(); ++i)
      text += fmt::format("{:.17g},{:.17g},{:.17g}\n", table.values(i, 0), std::ldexp(table.values(i, 1), k),
                          std::ldexp(table.values(i, 2), k));
    return WriteFile(name, text);
  };
  const std::string paths[] = {write("units_0.csv", 0), write("units_m38.csv", -38), write("units_p40.csv", 40)};
  for (const char* estimator : {"cauchy", "student:3"}) {
    std::vector<std::vector<double>> theta;
    for (const std::string& path : paths) {
      const CliResult r = RunCli(
          fmt::format("fit {} --output y --input u --na 2 --nb 2 --nk 1 --estimator {} --json", path, estimator));
      ASSERT_EQ(r.exit_code, 0) << r.err;
      theta.push_back(nlohmann::json::parse(r.out)["theta"].get<std::vector<double>>());
    }
    EXPECT_EQ(theta[1], theta[0]) << estimator << ", units 2^-38";
    EXPECT_EQ(theta[2], theta[0]) << estimator << ", units 2^40";
  }
}

// One estimator that cannot fit the data (the Kárný–Hangos recursion refuses dryer × 1e150 as numerically
// unsafe) is reported as that estimator's failure; the others keep their figures.
TEST(UsableResult, CompareReportsOneEstimatorsFailureBesideTheOthers) {
  const std::string big = ScaledDryer("dryer_e150.csv", 1e150);
  const CliResult r = RunCli("compare " + big + kUsableArx + " --estimators rls,cauchy --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  bool saw_rls = false, saw_cauchy = false;
  for (const auto& e : j["estimators"]) {
    if (e["estimator"] == "rls") {
      saw_rls = true;
      EXPECT_EQ(e["failed_trials"].get<int>(), 0);
      EXPECT_TRUE(e["failure"].is_null());
      EXPECT_GT(e["fit_percent"]["one_step"].get<double>(), 80.0);
    } else if (e["estimator"] == "cauchy") {
      saw_cauchy = true;
      EXPECT_EQ(e["failed_trials"].get<int>(), 1);
      EXPECT_NE(e["failure"].get<std::string>().find("refused as numerically unsafe"), std::string::npos)
          << e["failure"];
      EXPECT_TRUE(e["fit_percent"]["one_step"].is_null());
    }
  }
  EXPECT_TRUE(saw_rls && saw_cauchy);
  const CliResult table = RunCli("compare " + big + kUsableArx + " --estimators rls,cauchy");
  ASSERT_EQ(table.exit_code, 0) << table.err;
  EXPECT_NE(table.out.find("cauchy failed in 1 of 1 trials"), std::string::npos) << table.out;
  // Every estimator failing is an error.
  ExpectCliError("compare " + big + kUsableArx + " --estimators cauchy,student:3",
                 "every estimator failed on every trial");
}

// A record shorter than the robust start-up window: at the end of the data the start-up starts from every
// sample (SafeStudentRegression::FinishStartup), so the estimate is the data's, not its prior's (found by
// fuzz/fit_differential_fuzzer: θ ≈ 0 on the record × 2^-16, θ = (−2.8, −1.4) on the record). The same θ
// in any units, and within one reported standard error of least squares on these smooth, noise-free rows
// (the prior's θ ≈ 0 lies 1.5 standard errors from it).
TEST(UsableResult, RobustStartUpOfAShortRecordStartsFromEverySample) {
  std::string text = "u,y\n", scaled = "u,y\n";
  const double s = std::ldexp(1.0, -16);
  for (int t = 0; t < 12; ++t) {
    text += fmt::format("{},{}\n", std::sin(0.37 * t), std::cos(0.2 * t));
    scaled += fmt::format("{},{}\n", s * std::sin(0.37 * t), s * std::cos(0.2 * t));
  }
  const std::string model = " --output y --input u --na 1 --nb 1 --nk 2 --estimator ";
  const auto cauchy = UsableFitJson("fit " + WriteFile("short12.csv", text) + model + "cauchy");
  const auto tiny = UsableFitJson("fit " + WriteFile("short12_tiny.csv", scaled) + model + "cauchy");
  const auto rls = UsableFitJson("fit " + WriteFile("short12_rls.csv", text) + model + "rls");
  EXPECT_EQ(cauchy["lock_in"]["start_at_end"], true);
  EXPECT_EQ(cauchy["lock_in"]["start_window"], 4);  // every update of the 6 estimation rows from t0 = 2
  const auto dryer = UsableFitJson("fit dryer" + kUsableArx + " --estimator cauchy");
  EXPECT_EQ(dryer["lock_in"]["start_at_end"], false);
  EXPECT_EQ(dryer["lock_in"]["start_update"], 20);  // W = max(20, 4ρ)
  for (int i = 0; i < 2; ++i) {
    const double theta = cauchy["theta"][i], std = cauchy["theta_std"][i];
    EXPECT_NEAR(tiny["theta"][i].get<double>(), theta, 1e-9 * std::abs(theta)) << i;
    EXPECT_LT(std::abs(theta - rls["theta"][i].get<double>()), std) << i;
  }
}

// Predict(z) with a z of the wrong size is refused (it read past the parameter vector).
TEST(UsableResult, PredictChecksTheRegressorSize) {
  const Eigen::VectorXd short_z = Eigen::VectorXd::Ones(3), z = Eigen::VectorXd::Ones(4);
  RecursiveLeastSquares rls(4);
  EXPECT_THROW(rls.Predict(short_z), InvalidArgument);
  EXPECT_DOUBLE_EQ(rls.Predict(z), 0.0);
  StudentRegression student(4);
  EXPECT_THROW(student.Predict(Eigen::VectorXd::Ones(5)), InvalidArgument);
  SafeStudentRegression safe(4);
  EXPECT_THROW(safe.Predict(short_z), InvalidArgument);
  BatchRegressionEstimator batch(4);
  EXPECT_THROW(batch.Predict(short_z), InvalidArgument);
  for (const std::string name : {"rls", "cauchy", "student:3", "huber", "cauchy-ml"}) {
    auto any = MakeRegressionEstimator(ParseEstimatorSpec(name), 4);
    EXPECT_THROW(any->Predict(short_z), InvalidArgument) << name;
    try {
      any->Predict(short_z);
    } catch (const InvalidArgument& e) {
      EXPECT_STREQ(e.what(), "Predict: z has 3 entries; the model has 4 parameters") << name;
    }
  }
}

// A sampling period so small that the run holds no event would print a table of inf and NaN.
TEST(UsableResult, MemsRunWithoutEventsIsRefused) {
  ExpectCliError("mems --h 1e-300", "shorter than t_target = 0.3, the mean time between events");
  ExpectCliError("mems --h 1e-9 --steps 400 --grid-points 16 --t-mean 1",
                 "(steps - burn_in)·h = 3.6e-07 simulated seconds after the burn-in is shorter than t_target = 1");
}

}  // namespace
}  // namespace ident::testing
