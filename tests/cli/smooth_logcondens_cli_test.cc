// `ident logcondens` and `ident smooth` end to end: JSON output against the library (and logcondens
// golden values), and bad input with exit code 1 and a one-line message.
#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "tests/support/cli.h"

namespace ident::testing {
namespace {

const std::string kData = std::string(IDENT_SOURCE_DIR) + "/tests/density/data/";

void ExpectSmoothBadInput(const std::string& args, const std::string& needle) {
  const CliResult r = RunCli(args);
  EXPECT_EQ(r.exit_code, 1) << args << "\nstderr: " << r.err;
  EXPECT_NE(r.err.find(needle), std::string::npos) << args << "\nstderr: " << r.err;
  EXPECT_EQ(r.err.rfind("ident: error: ", 0), 0u) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << "more than one line: " << r.err;
  EXPECT_TRUE(r.out.empty()) << r.out;
}

TEST(LogcondensCommand, JsonHasKnotsPhiAndLoglikOfTheGoldenSample) {
  const CliResult r = RunCli("logcondens '" + kData + "laplace100_samples.csv' --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  const std::vector<double> knots = j["knots"], phi = j["phi"];
  ASSERT_EQ(knots.size(), 4u);  // logcondens: 4 knots (laplace100_knots.csv)
  EXPECT_EQ(phi.size(), knots.size());
  EXPECT_GE(j["loglik"].get<double>(), -170.24299121144401 * (1 + 1e-10));  // summary.csv, logcondens
  EXPECT_NEAR(j["loglik"].get<double>(), -170.24299121144401, 1e-5);
  EXPECT_EQ(j["n"], 100);
}

TEST(LogcondensCommand, PicksAColumnAndRejectsBadInput) {
  const std::string two = WriteFile("two.csv", "a,b\n1,5\n2,3\n4,4\n");
  const CliResult r = RunCli("logcondens '" + two + "' --column b --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(nlohmann::json::parse(r.out)["knots"].size(), 2u);
  ExpectSmoothBadInput("logcondens '" + two + "'", "pass --column");
  ExpectSmoothBadInput("logcondens '" + two + "' --column q", "no column 'q'");
  ExpectSmoothBadInput("logcondens '" + WriteFile("same.csv", "x\n2\n2\n") + "'", "at least 2 distinct");
  ExpectSmoothBadInput("logcondens /nonexistent.csv", "cannot open");
}

const char* kModel = R"({"F": [[1, 1], [0, 1]], "H": [[1, 1]],
  "initial": {"penalty": "quadratic", "covariance": [[1, 0], [0, 1]]},
  "process": {"penalty": "quadratic", "covariance": 1},
  "measurement": {"penalty": "huber", "kappa": 1}})";

TEST(SmoothCommand, ReportsTheStepsWhereTheDualDoesNotDetermineTheStates) {
  // Total-variation smoothing of a step (tests/smoothing/dual_reconstruction_test.cc solves it by hand):
  // y_t = 1 on the boundary of dom f* = [-1, 1] for t = 0..3, inside for t = 4, 5.
  const std::string model = WriteFile("tv.json", R"({"F": [[1]], "H": [[1]], "initial": {"penalty": "l1"},
    "process": {"penalty": "l1"}, "measurement": {"penalty": "quadratic", "covariance": 1}})");
  const std::string data = WriteFile("step.csv", "z\n0\n0\n0\n5\n5\n5\n");
  const CliResult r = RunCli("smooth --model '" + model + "' '" + data + "' --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  EXPECT_FALSE(j["reconstruction_unique"].get<bool>());
  EXPECT_EQ(j["nonunique_reconstruction_steps"].get<std::vector<int>>(), (std::vector<int>{0, 1, 2, 3}));
  EXPECT_NEAR(j["max_abs_x_from_dual_difference"].get<double>(), 14.0 / 3.0, 1e-4);
  const CliResult text = RunCli("smooth --model '" + model + "' '" + data + "'");
  ASSERT_EQ(text.exit_code, 0) << text.err;
  EXPECT_NE(text.out.find("not unique at 4 of 6 steps (f_t* has a kink at y_t): t = 0, 1, 2, 3\n"), std::string::npos)
      << text.out;
}

TEST(SmoothCommand, JsonReportsObjectivesGapStatesAndIterations) {
  const std::string model = WriteFile("model.json", kModel);
  const std::string data = WriteFile("data.csv", "z\n0.5\n1.2\n3.1\n2.0\n6.5\n");
  const CliResult r = RunCli("smooth --model '" + model + "' '" + data + "' --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  const double primal = j["primal"], dual = j["dual"];
  EXPECT_LE(std::abs(primal - dual), 1e-8 * std::abs(primal));
  EXPECT_EQ(j["x"].size(), 5u);
  EXPECT_EQ(j["x"][0].size(), 2u);
  EXPECT_GT(j["iterations"].get<int>(), 0);
  // Check optimality independently: (P) evaluated here at the printed x, and at perturbations of it.
  auto objective = [&](std::vector<std::vector<double>> x) {
    const double z[5] = {0.5, 1.2, 3.1, 2.0, 6.5};
    double sum = 0;
    for (int t = 0; t < 5; ++t) {
      double w0 = x[t][0], w1 = x[t][1];
      if (t > 0) w0 -= x[t - 1][0] + x[t - 1][1], w1 -= x[t - 1][1];
      const double r = std::abs(z[t] - x[t][0] - x[t][1]);
      sum += 0.5 * (w0 * w0 + w1 * w1) + (r <= 1 ? 0.5 * r * r : r - 0.5);
    }
    return sum;
  };
  const std::vector<std::vector<double>> x = j["x"];
  EXPECT_NEAR(objective(x), primal, 1e-12 * primal);
  for (int t = 0; t < 5; ++t)
    for (int i = 0; i < 2; ++i)
      for (double h : {-1e-5, 1e-5}) {
        auto xp = x;
        xp[t][i] += h;
        EXPECT_GT(objective(xp), primal);
      }
}

TEST(SmoothCommand, TextReportListsOneRowPerTime) {
  const std::string model = WriteFile("model.json", kModel);
  const std::string data = WriteFile("data.csv", "z\n0.5\n1.2\n3.1\n");
  const CliResult r = RunCli("smooth --model '" + model + "' '" + data + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("primal (P)"), std::string::npos);
  EXPECT_NE(r.out.find("dual   (D)"), std::string::npos);
  EXPECT_NE(r.out.find("gap"), std::string::npos);
  // stderr is not a terminal: at most progress lines (a run longer than 2 s, e.g. under a sanitizer).
  std::istringstream err(r.err);
  for (std::string line; std::getline(err, line);)
    EXPECT_EQ(line.rfind("ident smooth: ", 0), 0u) << "not a progress line: " << line;
}

TEST(SmoothCommand, BadModelsAndDataExitWithOneLine) {
  const std::string data = WriteFile("d.csv", "z\n0.5\n1.2\n3.1\n");
  auto model = [](const std::string& text) { return "'" + WriteFile("m.json", text) + "' "; };
  const std::string tail =
      R"(, "initial": {"penalty": "l1"}, "process": {"penalty": "l1"}, "measurement": {"penalty": "l1"}})";
  ExpectSmoothBadInput(
      "smooth --model " + model(R"({"F": [[1, 1], [0, 1]], "H": [[1, 1, 0]])" + tail) + "'" + data + "'",
      "F[0] is 2x2 but H has 3 columns");
  ExpectSmoothBadInput(
      "smooth --model " + model(R"({"F": [[1, 1], [0, 1]], "H": [[1, 1], [1, 0]])" + tail) + "'" + data + "'",
      "H has 2 rows but the data have 1 measurement columns");
  ExpectSmoothBadInput(
      "smooth --model " +
          model(
              R"({"F": [[1, 1], [0, 1]], "H": [[1, 1]], "initial": {"penalty": "huber"}, "process": {"penalty": "l1"}, "measurement": {"penalty": "l1"}})") +
          "'" + data + "'",
      "initial: missing \"kappa\"");
  ExpectSmoothBadInput(
      "smooth --model " +
          model(
              R"({"F": [[1, 1], [0, 1]], "H": [[1, 1]], "initial": {"penalty": "l1"}, "process": {"penalty": "cauchy"}, "measurement": {"penalty": "l1"}})") +
          "'" + data + "'",
      "unknown penalty 'cauchy'");
  ExpectSmoothBadInput("smooth --model " + model(R"({"F": [[1, 1], [0, 1]], "H": [[1, 1]]})") + "'" + data + "'",
                       "missing \"initial\"");
  ExpectSmoothBadInput("smooth --model " + model("{\"F\": [[1]") + "'" + data + "'", "not valid JSON");
  ExpectSmoothBadInput("smooth --model " + model(R"({"F": [[1, 1], [0, 1]], "H": [[1, 1]])" + tail) + "'" +
                           WriteFile("y.csv", "y\n1\n2\n") + "'",
                       "no measurement column");
  // Infeasible: |w_t| <= 0.1 and |z_t - x_t| <= 0.1 cannot hold when z jumps by 3.
  const std::string box = R"({"penalty": "piecewise_linear", "knots": [-0.1, 0.1], "values": [0, 0]})";
  ExpectSmoothBadInput("smooth --model " +
                           model("{\"F\": [[1]], \"H\": [[1]], \"initial\": " + box + ", \"process\": " + box +
                                 ", \"measurement\": " + box + "}") +
                           "'" + data + "'",
                       "no state sequence keeps every residual inside");
}

}  // namespace
}  // namespace ident::testing
