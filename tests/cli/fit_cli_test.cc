// `ident fit` end to end: the datasets README baselines, JSON schema, trace file, and every bad input
// of the foundation issue with its exit code and one-line message.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "tests/support/cli.h"
#include "tests/support/test_data.h"

namespace ident::testing {
namespace {

const std::string kDryerArx = " --output y --input u --na 2 --nb 2 --nk 3";

nlohmann::json FitJson(const std::string& args) {
  const CliResult r = RunCli("fit " + args + " --json");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  return nlohmann::json::parse(r.out);
}

TEST(FitCommand, DryerRlsReproducesTheDatasetsReadmeBaseline) {
  const nlohmann::json j = FitJson("datasets/dryer.csv" + kDryerArx + " --estimator rls");
  EXPECT_EQ(j["estimator"], "rls");
  EXPECT_EQ(j["structure"], "ARX(2,2,3)");
  const std::vector<double> theta = j["theta"];
  const std::vector<double> readme = {-1.27654, 0.396711, 0.0651903, 0.0451792};
  ASSERT_EQ(theta.size(), 4u);
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(theta[i], readme[i], 5e-6 * std::abs(readme[i])) << i;
  EXPECT_NEAR(j["fit_percent"]["one_step"].get<double>(), 95.04, 0.005);
  EXPECT_NEAR(j["fit_percent"]["simulation"].get<double>(), 85.57, 0.005);
  EXPECT_NEAR(j["rms"]["one_step"].get<double>(), 0.0407, 0.00005);
  EXPECT_NEAR(j["rms"]["simulation"].get<double>(), 0.1185, 0.00005);
  EXPECT_EQ(j["samples_estimation"], 500);
  EXPECT_EQ(j["samples_validation"], 500);
  EXPECT_EQ(j["theta_std"].size(), 4u);
  EXPECT_GT(j["noise_std"].get<double>(), 0.03);
  EXPECT_LT(j["noise_std"].get<double>(), 0.05);
}

TEST(FitCommand, GasFurnaceReproducesTheReadmeValidationFits) {
  const nlohmann::json j = FitJson("gas_furnace --output y --input u --na 2 --nb 2 --nk 3");
  EXPECT_NEAR(j["fit_percent"]["one_step"].get<double>(), 83.91, 0.005);
  EXPECT_NEAR(j["fit_percent"]["simulation"].get<double>(), 53.76, 0.005);
}

TEST(FitCommand, BareDatasetNameEqualsPath) {
  const nlohmann::json a = FitJson("dryer" + kDryerArx);
  const nlohmann::json b = FitJson("datasets/dryer.csv" + kDryerArx);
  EXPECT_EQ(a["theta"], b["theta"]);
}

TEST(FitCommand, HumanReportShowsParametersAndFits) {
  const CliResult r = RunCli("fit dryer" + kDryerArx);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("ARX(2,2,3)"), std::string::npos);
  EXPECT_NE(r.out.find("-1.27654"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("one-step 95.04 %"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("simulation 85.57 %"), std::string::npos) << r.out;
}

TEST(FitCommand, HeaderSaysWhenFewerPassesWereMadeThanAsked) {
  const std::string stars = "stars_cyg --output log_light --regressors log_Te --passes 3 --estimator ";
  for (const std::string e : {"lc:laplace", "rls", "huber"}) {
    const CliResult r = RunCli("fit " + stars + e);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.out.find("1 pass of the 3 asked: " + e + " makes no further passes"), std::string::npos) << r.out;
    EXPECT_EQ(FitJson(stars + e)["passes"], 1) << e;
  }
  const CliResult cauchy = RunCli("fit " + stars + "cauchy");
  ASSERT_EQ(cauchy.exit_code, 0) << cauchy.err;
  EXPECT_NE(cauchy.out.find("(recursive, 3 passes, mean detrending)"), std::string::npos) << cauchy.out;
}

TEST(FitCommand, TraceHasOneRowPerUpdateEndingAtTheFinalEstimate) {
  const std::string trace = TempDir() + "/trace.csv";
  const nlohmann::json j = FitJson("dryer" + kDryerArx + " --trace " + trace);
  std::vector<std::string> names;
  const Eigen::MatrixXd t = ReadCsvMatrix(trace, &names);
  EXPECT_EQ(names,
            (std::vector<std::string>{"t", "nu", "beta", "pred_err", "theta1", "theta2", "theta3", "theta4", "Dy"}));
  ASSERT_EQ(t.rows(), j["updates"].get<int>());
  EXPECT_EQ(t(0, 0), 5);  // first regression at row t0 + 1 = 5 (1-based)
  const std::vector<double> theta = j["theta"];
  for (int i = 0; i < 4; ++i) EXPECT_DOUBLE_EQ(t(t.rows() - 1, 4 + i), theta[i]);
  // RLS: β = 1/ν on every row.
  EXPECT_LT((t.col(2).array() * t.col(1).array() - 1).abs().maxCoeff(), 1e-12);
}

TEST(FitCommand, StaticRegressionWithInterceptRecoversAnExactLinearLaw) {
  std::string csv = "x1,x2,y\n";
  for (int i = 0; i < 40; ++i) {
    const double x1 = std::sin(i), x2 = std::cos(3 * i) + 0.1 * i;
    csv += std::to_string(x1) + "," + std::to_string(x2) + "," + std::to_string(2 + 3 * x1 - x2) + "\n";
  }
  const std::string path = WriteFile("linear.csv", csv);
  const nlohmann::json j = FitJson(path + " --output y --regressors x1,x2 --intercept --split 1");
  const std::vector<double> theta = j["theta"];
  EXPECT_NEAR(theta[0], 2, 1e-5);
  EXPECT_NEAR(theta[1], 3, 1e-5);
  EXPECT_NEAR(theta[2], -1, 1e-5);
  EXPECT_EQ(j["detrend"], "none");  // the default with an intercept
  EXPECT_TRUE(j["fit_percent"]["simulation"].is_null());
}

TEST(FitCommand, MissingSamplesAreSkippedWhenAsked) {
  std::string csv = ReadFile(DatasetPath("dryer.csv"));
  const std::size_t pos = csv.find("\n", csv.find("\n", 2000) + 1);
  const std::size_t end = csv.find("\n", pos + 1);
  csv.replace(pos + 1, end - pos - 1, csv.substr(pos + 1, csv.find(',', pos + 1) - pos - 1) + ",nan,4.5");
  const std::string path = WriteFile("dryer_missing.csv", csv);
  ExpectCliError("fit " + path + kDryerArx, "is not a finite number");
  const nlohmann::json j = FitJson(path + kDryerArx + " --missing");
  EXPECT_GE(j["rejected"].get<int>(), 1);
}

// Item 7 of the foundation issue: every bad input, its exit code and its message.
TEST(FitCommand, BadDataFilesAreReportedWithFileLineAndColumn) {
  ExpectCliError("fit /nonexistent.csv" + kDryerArx, "cannot open '/nonexistent.csv'");
  ExpectCliError("fit " + WriteFile("empty.csv", "") + kDryerArx, "empty.csv: the file is empty");
  ExpectCliError("fit " + WriteFile("header.csv", "t,u,y\n") + kDryerArx, "header.csv: no data rows after the header");
  ExpectCliError("fit " + WriteFile("ragged.csv", "t,u,y\n0,1,2\n1,2\n") + kDryerArx,
                 "ragged.csv:3: row has 2 fields; the header has 3");
  ExpectCliError("fit " + WriteFile("text.csv", "t,u,y\n0,1,2\n1,x1,2\n") + kDryerArx,
                 "text.csv:3: column 2 ('u'): 'x1' is not a number");
  ExpectCliError("fit " + WriteFile("inf.csv", "t,u,y\n0,1,inf\n") + kDryerArx,
                 "inf.csv:2: column 3 ('y'): 'inf' is not a finite number");
  ExpectCliError("fit " + WriteFile("dup.csv", "t,u,u\n0,1,2\n") + kDryerArx, "dup.csv:1: duplicate column name 'u'");
  ExpectCliError("fit dryer --output y --input q --na 2 --nb 2 --nk 3", "no column 'q' (columns: t, u, y)");
  ExpectCliError("fit dryer --output yy --input u", "no column 'yy'");
}

TEST(FitCommand, UnidentifiableModelsAreRefused) {
  std::string constant = "t,u,y\n";
  for (int i = 0; i < 50; ++i) constant += std::to_string(i) + ",1.5," + std::to_string(std::sin(0.3 * i)) + "\n";
  ExpectCliError("fit " + WriteFile("const.csv", constant) + " --output y --input u --na 1 --nb 1 --nk 1",
                 "regressor 'b1' is identically zero");
  std::string collinear = "x1,x2,y\n";
  for (int i = 0; i < 50; ++i)
    collinear +=
        std::to_string(std::sin(i)) + "," + std::to_string(2 * std::sin(i)) + "," + std::to_string(i % 7) + "\n";
  ExpectCliError("fit " + WriteFile("collinear.csv", collinear) + " --output y --regressors x1,x2", "collinear");
  ExpectCliError("fit gas_furnace --output y --input u --na 100 --nb 50 --nk 3", "the estimation part has 148 rows");
}

TEST(FitCommand, BadOptionsExitOneAndNameTheOption) {
  ExpectCliError("fit dryer" + kDryerArx + " --forgetting 1.5", "forgetting = 1.5; need 0 < forgetting <= 1");
  ExpectCliError("fit dryer" + kDryerArx + " --forgetting 0", "forgetting = 0");
  ExpectCliError("fit dryer" + kDryerArx + " --estimator nonesuch", "unknown estimator 'nonesuch'");
  ExpectCliError("fit dryer" + kDryerArx + " --split 1.5", "split = 1.5");
  ExpectCliError("fit dryer" + kDryerArx + " --nu0 -1 --vy0 1 --vz0 1", "nu0 = -1");
  ExpectCliError("fit dryer" + kDryerArx + " --nu0 5 --vy0 -1 --vz0 1", "vy0 = -1");
  ExpectCliError("fit dryer --output y --input u --na -1", "na = -1");
  ExpectCliError("fit dryer --output y --input u --nb 2,2", "--nb has 2 values");
  ExpectCliError("fit dryer" + kDryerArx + " --prior /nonexistent.json", "cannot open prior file");
  ExpectCliError("fit dryer" + kDryerArx + " --prior " + WriteFile("p.json", "{\"nu0\": 5, \"V0\": [[1,0],[0,1]]}"),
                 "V0 has 2 rows; the model needs 5x5");
  ExpectCliError("fit dryer" + kDryerArx + " --prior " + WriteFile("q.json", "{nu0: 5"), "not valid JSON");
}

TEST(FitCommand, UsageErrorsExitTwo) {
  EXPECT_EQ(RunCli("fit dryer --output y --input u --bogus").exit_code, 2);
  EXPECT_EQ(RunCli("fit dryer --input u").exit_code, 2);       // --output is required
  EXPECT_EQ(RunCli("fit --output y --input u").exit_code, 2);  // DATA is required
  EXPECT_EQ(RunCli("fit dryer --output y --input u --detrend linear").exit_code, 2);
  EXPECT_EQ(RunCli("fit dryer --output y --input u --regressors u").exit_code, 2);  // excludes --input
  EXPECT_EQ(RunCli("fit dryer --output y --input u --nu0 3").exit_code, 2);         // needs --vy0 --vz0
  EXPECT_EQ(RunCli("").exit_code, 2);
  EXPECT_EQ(RunCli("fit --help").exit_code, 0);
}

}  // namespace
}  // namespace ident::testing
