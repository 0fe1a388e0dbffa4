// `ident fit` on several experiments (several files, --experiment-column): no regressor straddles two
// experiments. Checked against least squares and a simulation built by hand from each experiment's rows.
#include <cmath>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <Eigen/Dense>
#include <nlohmann/json.hpp>

#include "common/dense_decompositions.h"
#include "tests/cli/experiment_records.h"
#include "tests/support/cli.h"

namespace ident::testing {
namespace {

nlohmann::json ExperimentsFitJson(const std::string& args) {
  const CliResult r = RunCli("fit " + args + " --json");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  return nlohmann::json::parse(r.out);
}

const std::string kExperimentsArx =
    " --output y --input u --na 2 --nb 2 --nk 1 --estimator rls --split 1 --detrend none";

class Experiments : public ::testing::Test {
 protected:
  std::vector<ExperimentRecord> records = {SimulateExperiment(300, 1, 0.0), SimulateExperiment(250, 2, 5.0)};
  std::string a = WriteFile("exp_a.csv", ExperimentsCsv({records[0]}, false));
  std::string b = WriteFile("exp_b.csv", ExperimentsCsv({records[1]}, false));
  std::string joined = WriteFile("exp_ab.csv", ExperimentsCsv(records, false));
  std::string labelled = WriteFile("exp_runs.csv", ExperimentsCsv(records, true));
};

TEST_F(Experiments, TwoFilesEqualLeastSquaresOfEachExperimentsOwnRegressors) {
  Eigen::MatrixXd Z;
  Eigen::VectorXd Y;
  ExperimentRegressors(records, Z, Y);
  const Eigen::VectorXd ls = dense::ColPivQr(Z).solve(Y);
  const nlohmann::json j = ExperimentsFitJson(a + " " + b + kExperimentsArx);
  const std::vector<double> theta = j["theta"];
  ASSERT_EQ(theta.size(), 4u);
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(theta[i], ls(i), 1e-12) << i;
  EXPECT_EQ(j["updates"], 298 + 248);
  ASSERT_EQ(j["experiments"].size(), 2u);
  EXPECT_EQ(j["experiments"][0]["name"], a);
  EXPECT_EQ(j["experiments"][0]["rows"], nlohmann::json::array({1, 300}));
  EXPECT_EQ(j["experiments"][1]["name"], b);
  EXPECT_EQ(j["experiments"][1]["rows"], nlohmann::json::array({301, 550}));

  // The concatenated file as one record has the two straddling regressors: another estimate.
  const nlohmann::json one = ExperimentsFitJson(joined + kExperimentsArx);
  EXPECT_EQ(one["updates"], 548);
  const std::vector<double> straddled = one["theta"];
  double difference = 0;
  for (int i = 0; i < 4; ++i) difference = std::max(difference, std::abs(straddled[i] - ls(i)));
  EXPECT_GT(difference, 1e-4);
  ASSERT_EQ(one["experiments"].size(), 1u);
  EXPECT_EQ(one["experiments"][0]["rows"], nlohmann::json::array({1, 550}));
}

TEST_F(Experiments, ExperimentColumnEqualsSeparateFiles) {
  const nlohmann::json files = ExperimentsFitJson(a + " " + b + kExperimentsArx);
  const nlohmann::json column = ExperimentsFitJson(labelled + kExperimentsArx + " --experiment-column run");
  EXPECT_EQ(column["theta"], files["theta"]);
  EXPECT_EQ(column["fit_percent"], files["fit_percent"]);
  ASSERT_EQ(column["experiments"].size(), 2u);
  EXPECT_EQ(column["experiments"][0]["name"], "1");
  EXPECT_EQ(column["experiments"][1]["rows"], nlohmann::json::array({301, 550}));
}

// The validation simulation restarts in each experiment from its own first two measured outputs.
TEST_F(Experiments, SimulationRestartsInEachExperiment) {
  const nlohmann::json j = ExperimentsFitJson(a + " " + b + kExperimentsArx);
  const std::vector<double> th = j["theta"];
  std::vector<double> y, yhat;
  for (const ExperimentRecord& r : records) {
    std::vector<double> s(r.y.begin(), r.y.begin() + 2);
    for (std::size_t t = 2; t < r.y.size(); ++t) {
      s.push_back(-th[0] * s[t - 1] - th[1] * s[t - 2] + th[2] * r.u[t - 1] + th[3] * r.u[t - 2]);
      y.push_back(r.y[t]);
      yhat.push_back(s[t]);
    }
  }
  double mean = 0;
  for (double v : y) mean += v / static_cast<double>(y.size());
  double err = 0, dev = 0;
  for (std::size_t i = 0; i < y.size(); ++i) {
    err += (y[i] - yhat[i]) * (y[i] - yhat[i]);
    dev += (y[i] - mean) * (y[i] - mean);
  }
  const double fit = 100 * (1 - std::sqrt(err / dev));
  EXPECT_NEAR(j["fit_percent"]["simulation"].get<double>(), fit, 1e-9);
}

TEST_F(Experiments, ReportListsTheExperimentsRows) {
  const CliResult r = RunCli("fit " + labelled + kExperimentsArx + " --experiment-column run");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("2 experiments (regressors restart at each): 1 rows 1-300, 2 rows 301-550"), std::string::npos)
      << r.out;
}

TEST_F(Experiments, FilesWithOtherColumnsAreRefusedByName) {
  const std::string other = WriteFile("exp_other.csv", "u,x\n1,2\n3,4\n5,6\n");
  ExpectCliError("fit " + a + " " + other + kExperimentsArx, "exp_other.csv: columns (u, x) differ from");
  ExpectCliError("fit " + a + kExperimentsArx + " --experiment-column run", "no column 'run'");
}

}  // namespace
}  // namespace ident::testing
