// Several experiments (several files, --experiment-column) and the time column's gaps in `ident orders`,
// `ident compare` and `ident predict`, and the saved model's per-file checksums. Every figure is checked
// against least squares, predictions or checksums built by hand from each experiment's (or each gap-free
// piece's) own rows.
#include <cmath>
#include <cstdint>
#include <sstream>
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

struct PieceFit {
  Eigen::VectorXd theta;
  double loss = 0;  // mean square of the residuals
  int samples = 0;
};

// z(t) = (−y(t−1) … −y(t−na), u(t−nk) … u(t−nk−nb+1)) for t = t0 … n−1 of each piece alone.
void PieceRegressors(const std::vector<ExperimentRecord>& pieces, int na, int nb, int nk, int t0, Eigen::MatrixXd& Z,
                     Eigen::VectorXd& Y) {
  std::vector<Eigen::VectorXd> rows;
  std::vector<double> ys;
  for (const ExperimentRecord& p : pieces)
    for (int t = t0; t < static_cast<int>(p.y.size()); ++t) {
      Eigen::VectorXd z(na + nb);
      for (int i = 1; i <= na; ++i) z(i - 1) = -p.y[static_cast<std::size_t>(t - i)];
      for (int l = 0; l < nb; ++l) z(na + l) = p.u[static_cast<std::size_t>(t - nk - l)];
      rows.push_back(z);
      ys.push_back(p.y[static_cast<std::size_t>(t)]);
    }
  Z.resize(static_cast<Eigen::Index>(rows.size()), na + nb);
  Y.resize(static_cast<Eigen::Index>(rows.size()));
  for (std::size_t i = 0; i < rows.size(); ++i) {
    Z.row(static_cast<Eigen::Index>(i)) = rows[i].transpose();
    Y(static_cast<Eigen::Index>(i)) = ys[i];
  }
}

PieceFit PieceLeastSquares(const std::vector<ExperimentRecord>& pieces, int na, int nb, int nk, int t0) {
  Eigen::MatrixXd Z;
  Eigen::VectorXd Y;
  PieceRegressors(pieces, na, nb, nk, t0, Z, Y);
  PieceFit r;
  r.theta = dense::ColPivQr(Z).solve(Y);
  r.samples = static_cast<int>(Y.size());
  r.loss = (Y - Z * r.theta).squaredNorm() / r.samples;
  return r;
}

// Mean square of the one-step residuals of θ over the pieces (rows t ≥ t0 of each).
double PieceLoss(const std::vector<ExperimentRecord>& pieces, int na, int nb, int nk, int t0,
                 const Eigen::VectorXd& theta) {
  Eigen::MatrixXd Z;
  Eigen::VectorXd Y;
  PieceRegressors(pieces, na, nb, nk, t0, Z, Y);
  return (Y - Z * theta).squaredNorm() / static_cast<double>(Y.size());
}

// Fit % = 100 (1 − ‖y − ŷ‖/‖y − ȳ‖) over the pairs given.
double HandFitPercent(const std::vector<double>& y, const std::vector<double>& y_hat) {
  double mean = 0;
  for (double v : y) mean += v / static_cast<double>(y.size());
  double ee = 0, yy = 0;
  for (std::size_t i = 0; i < y.size(); ++i) {
    ee += (y[i] - y_hat[i]) * (y[i] - y_hat[i]);
    yy += (y[i] - mean) * (y[i] - mean);
  }
  return 100 * (1 - std::sqrt(ee / yy));
}

ExperimentRecord PieceRows(const ExperimentRecord& r, std::size_t first, std::size_t end) {
  return {{r.u.begin() + static_cast<std::ptrdiff_t>(first), r.u.begin() + static_cast<std::ptrdiff_t>(end)},
          {r.y.begin() + static_cast<std::ptrdiff_t>(first), r.y.begin() + static_cast<std::ptrdiff_t>(end)}};
}

nlohmann::json CommandJson(const std::string& args) {
  const CliResult r = RunCli(args);
  EXPECT_EQ(r.exit_code, 0) << args << "\n" << r.err;
  return r.exit_code == 0 ? nlohmann::json::parse(r.out) : nlohmann::json();
}

void ExpectTwoExperiments(const nlohmann::json& j, const std::string& first, const std::string& second) {
  ASSERT_EQ(j["experiments"].size(), 2u) << j["experiments"];
  EXPECT_EQ(j["experiments"][0]["name"], first);
  EXPECT_EQ(j["experiments"][0]["rows"], nlohmann::json::array({1, 300}));
  EXPECT_EQ(j["experiments"][1]["name"], second);
  EXPECT_EQ(j["experiments"][1]["rows"], nlohmann::json::array({301, 550}));
}

const std::string kArx221 = " --output y --input u --na 2 --nb 2 --nk 1";

class ExperimentCommands : public ::testing::Test {
 protected:
  std::vector<ExperimentRecord> records = {SimulateExperiment(300, 11, 0.0), SimulateExperiment(250, 12, 5.0)};
  std::string a = WriteFile("cmd_a.csv", ExperimentsCsv({records[0]}, false));
  std::string b = WriteFile("cmd_b.csv", ExperimentsCsv({records[1]}, false));
  std::string labelled = WriteFile("cmd_runs.csv", ExperimentsCsv(records, true));
};

// Every structure's loss and θ are least squares on the rows t ≥ T0 of each experiment alone (T0 = 3 for the
// grid's largest lags), and the two ways of giving the experiments agree.
TEST_F(ExperimentCommands, OrdersFitEachStructureOnEveryExperimentsOwnRows) {
  const std::string grid = " --output y --input u --na 1:3 --nb 1:2 --nk 1:2 --split 1 --detrend none --json";
  const nlohmann::json j = CommandJson("orders " + a + " " + b + grid);
  ExpectTwoExperiments(j, a, b);
  EXPECT_EQ(j["samples"], 297 + 247);
  ASSERT_EQ(j["structures"].size(), 12u);
  for (const nlohmann::json& s : j["structures"]) {
    const int na = s["na"], nb = s["nb"], nk = s["nk"];
    const PieceFit ls = PieceLeastSquares(records, na, nb, nk, 3);
    EXPECT_NEAR(s["loss"].get<double>(), ls.loss, 1e-10 * ls.loss) << na << nb << nk;
    const std::vector<double> theta = s["theta"];
    for (int i = 0; i < ls.theta.size(); ++i) EXPECT_NEAR(theta[static_cast<std::size_t>(i)], ls.theta(i), 1e-8);
  }
  const nlohmann::json column = CommandJson("orders " + labelled + grid + " --experiment-column run");
  EXPECT_EQ(column["structures"], j["structures"]);
  ExpectTwoExperiments(column, "1", "2");
}

// With a split inside the first experiment, estimation is its first 275 rows, validation its last 25 rows
// (a segment of their own) and the second experiment.
TEST_F(ExperimentCommands, OrdersValidationRestartsAtTheSplitAndAtEachExperiment) {
  const nlohmann::json j =
      CommandJson("orders " + a + " " + b + " --output y --input u --na 1:2 --nb 1:2 --nk 1 --detrend none --json");
  const std::vector<ExperimentRecord> estimation = {PieceRows(records[0], 0, 275)};
  const std::vector<ExperimentRecord> validation = {PieceRows(records[0], 275, 300), records[1]};
  EXPECT_EQ(j["samples"], 273);
  EXPECT_EQ(j["validation_samples"], 23 + 248);
  for (const nlohmann::json& s : j["structures"]) {
    const int na = s["na"], nb = s["nb"];
    const PieceFit ls = PieceLeastSquares(estimation, na, nb, 1, 2);
    EXPECT_NEAR(s["loss"].get<double>(), ls.loss, 1e-10 * ls.loss);
    const double v = PieceLoss(validation, na, nb, 1, 2, ls.theta);
    EXPECT_NEAR(s["validation_loss"].get<double>(), v, 1e-9 * v) << na << nb;
  }
}

// The clean-data least-squares reference of compare is least squares on each experiment's own regressors, and
// its one-step fit % is scored on each experiment's rows t ≥ 2.
TEST_F(ExperimentCommands, CompareReferenceIsLeastSquaresOfTheExperimentsOwnRegressors) {
  const std::string options = kArx221 + " --split 1 --detrend none --outliers none --estimators rls --json";
  const nlohmann::json j = CommandJson("compare " + a + " " + b + options);
  ExpectTwoExperiments(j, a, b);
  const PieceFit ls = PieceLeastSquares(records, 2, 2, 1, 2);
  const std::vector<double> theta = j["reference"]["theta"];
  ASSERT_EQ(theta.size(), 4u);
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(theta[static_cast<std::size_t>(i)], ls.theta(i), 1e-9) << i;
  std::vector<double> y, y_hat;
  for (const ExperimentRecord& r : records)
    for (std::size_t t = 2; t < r.y.size(); ++t) {
      y.push_back(r.y[t]);
      y_hat.push_back(-ls.theta(0) * r.y[t - 1] - ls.theta(1) * r.y[t - 2] + ls.theta(2) * r.u[t - 1] +
                      ls.theta(3) * r.u[t - 2]);
    }
  EXPECT_NEAR(j["reference"]["fit_percent"]["one_step"].get<double>(), HandFitPercent(y, y_hat), 1e-7);
  const nlohmann::json column = CommandJson("compare " + labelled + options + " --experiment-column run");
  EXPECT_EQ(column["reference"], j["reference"]);
  ExpectTwoExperiments(column, "1", "2");
}

// predict on the two experiments: one-step and 2-step predictions built by hand per experiment from the saved θ.
TEST_F(ExperimentCommands, PredictRestartsTheRegressorsAndTheKStepRecursionAtEachExperiment) {
  const std::string model = TempDir() + "/cmd_model.json";
  ASSERT_EQ(
      RunCli("fit " + a + " " + b + kArx221 + " --split 1 --detrend none --estimator rls --save " + model).exit_code,
      0);
  const std::vector<double> th = nlohmann::json::parse(ReadFile(model))["theta"];
  const nlohmann::json j = CommandJson("predict " + model + " " + a + " " + b + " --horizon 2 --json");
  ExpectTwoExperiments(j, a, b);
  std::vector<double> y, one, two;
  for (const ExperimentRecord& r : records) {
    auto predict = [&](std::size_t t, double y1) {  // ŷ(t) with y(t−1) = y1, the rest measured
      return -th[0] * y1 - th[1] * r.y[t - 2] + th[2] * r.u[t - 1] + th[3] * r.u[t - 2];
    };
    for (std::size_t t = 2; t < r.y.size(); ++t) {
      y.push_back(r.y[t]);
      one.push_back(predict(t, r.y[t - 1]));
      two.push_back(predict(t, t - 1 >= 2 ? predict(t - 1, r.y[t - 2]) : r.y[t - 1]));
    }
  }
  EXPECT_EQ(j["samples"], 298 + 248);
  EXPECT_NEAR(j["fit_percent"]["one_step"].get<double>(), HandFitPercent(y, one), 1e-9);
  EXPECT_NEAR(j["k_step"]["fit_percent"].get<double>(), HandFitPercent(y, two), 1e-9);
  // The CSV names each row's experiment; the second's first two rows have no regressor.
  const CliResult csv = RunCli("predict " + model + " " + labelled + " --experiment-column run");
  ASSERT_EQ(csv.exit_code, 0) << csv.err;
  EXPECT_NE(csv.out.find("row,y,one_step,residual,experiment\n"), std::string::npos);
  EXPECT_NE(csv.out.find("\n301," + fmt::format("{}", records[1].y[0]) + ",nan,nan,2\n"), std::string::npos);
  const std::size_t at = csv.out.find("\n303,");
  ASSERT_NE(at, std::string::npos);
  std::istringstream line(csv.out.substr(at + 1, csv.out.find('\n', at + 1) - at - 1));
  std::vector<std::string> cells;
  for (std::string cell; std::getline(line, cell, ',');) cells.push_back(cell);
  ASSERT_EQ(cells.size(), 5u);
  EXPECT_EQ(std::stod(cells[1]), records[1].y[2]);
  EXPECT_NEAR(std::stod(cells[2]), one[298], 1e-12);  // experiment 1 gives one[0 … 297]
  EXPECT_EQ(cells[4], "2");
}

std::vector<nlohmann::json> JsonLines(const std::string& out) {
  std::vector<nlohmann::json> lines;
  std::istringstream in(out);
  for (std::string line; std::getline(in, line);) lines.push_back(nlohmann::json::parse(line));
  return lines;
}

// ident stream --experiment-column restarts the regressors where the label changes: RLS ends at least squares on
// each experiment's own regressors, the Cauchy estimator at ident fit's estimate on the same experiments.
TEST_F(ExperimentCommands, StreamRestartsTheRegressorsWhereTheLabelChanges) {
  const CliResult rls = RunCli("stream " + labelled + kArx221 + " --estimator rls --experiment-column run");
  ASSERT_EQ(rls.exit_code, 0) << rls.err;
  const std::vector<nlohmann::json> lines = JsonLines(rls.out);
  ASSERT_EQ(lines.size(), 550u);
  for (std::size_t row : {1u, 2u, 301u, 302u}) EXPECT_EQ(lines[row - 1]["status"], "start-up") << row;
  EXPECT_EQ(lines[302]["status"], "ok");
  const PieceFit ls = PieceLeastSquares(records, 2, 2, 1, 2);
  const std::vector<double> theta = lines.back()["theta"];
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(theta[static_cast<std::size_t>(i)], ls.theta(i), 1e-8) << i;

  const std::string cauchy = kArx221 + " --estimator cauchy --experiment-column run";
  const CliResult streamed = RunCli("stream " + labelled + cauchy);
  ASSERT_EQ(streamed.exit_code, 0) << streamed.err;
  const nlohmann::json fit = CommandJson("fit " + labelled + cauchy + " --split 1 --detrend none --json");
  EXPECT_EQ(JsonLines(streamed.out).back()["theta"], fit["theta"]);
  ExpectCliError("stream " + labelled + kArx221 + " --experiment-column runs", "no column 'runs'");
}

// FNV-1a, 64 bits (offset basis 14695981039346656037, prime 1099511628211), as 16 hex digits.
std::string HandFnv1a64(const std::string& bytes) {
  std::uint64_t h = 14695981039346656037ull;
  for (unsigned char c : bytes) {
    h ^= c;
    h *= 1099511628211ull;
  }
  return fmt::format("{:016x}", h);
}

TEST_F(ExperimentCommands, SavedModelListsEveryFileWithItsChecksum) {
  const std::string model = TempDir() + "/cmd_files.json";
  ASSERT_EQ(RunCli("fit " + a + " " + b + kArx221 + " --save " + model).exit_code, 0);
  const nlohmann::json data = nlohmann::json::parse(ReadFile(model))["data"];
  EXPECT_EQ(data["fnv1a64"], "");  // the existing key keeps its type: no one checksum for two files
  EXPECT_EQ(data["rows"], 550);
  ASSERT_EQ(data["files"].size(), 2u);
  EXPECT_EQ(data["files"][0]["path"], a);
  EXPECT_EQ(data["files"][0]["rows"], 300);
  EXPECT_EQ(data["files"][0]["fnv1a64"], HandFnv1a64(ReadFile(a)));
  EXPECT_EQ(data["files"][1]["path"], b);
  EXPECT_EQ(data["files"][1]["rows"], 250);
  EXPECT_EQ(data["files"][1]["fnv1a64"], HandFnv1a64(ReadFile(b)));
  // One file: its checksum under both keys.
  ASSERT_EQ(RunCli("fit " + a + kArx221 + " --save " + model).exit_code, 0);
  const nlohmann::json one = nlohmann::json::parse(ReadFile(model))["data"];
  EXPECT_EQ(one["fnv1a64"], HandFnv1a64(ReadFile(a)));
  ASSERT_EQ(one["files"].size(), 1u);
  EXPECT_EQ(one["files"][0]["fnv1a64"], one["fnv1a64"]);
}

// A record with a time column t whose rows 201-203 (t = 20.0, 20.1, 20.2) were not recorded.
class TimeGapCommands : public ::testing::Test {
 protected:
  ExperimentRecord all = SimulateExperiment(403, 21, 1.0);
  std::vector<ExperimentRecord> pieces = {PieceRows(all, 0, 200), PieceRows(all, 203, 403)};
  std::string path = WriteFile("gap.csv", [this] {
    std::string text = "t,u,y\n";
    for (std::size_t i = 0; i < all.y.size(); ++i)
      if (i < 200 || i >= 203)
        text += fmt::format("{:.1f},{:.17g},{:.17g}\n", 0.1 * static_cast<double>(i), all.u[i], all.y[i]);
    return text;
  }());
};

void ExpectOneTimeGap(const nlohmann::json& j, long filled) {
  ASSERT_TRUE(j["time_gaps"].is_array()) << j["time_gaps"];
  ASSERT_EQ(j["time_gaps"].size(), 1u);
  EXPECT_EQ(j["time_gaps"][0]["row"], 201);
  EXPECT_NEAR(j["time_gaps"][0]["t_before"].get<double>(), 19.9, 1e-12);
  EXPECT_NEAR(j["time_gaps"][0]["t_after"].get<double>(), 20.3, 1e-12);
  EXPECT_EQ(j["time_gaps"][0]["missing"], 3);
  EXPECT_EQ(j["time_gaps"][0]["filled"], filled);
}

// Filled under --missing, the gap splits the record: each structure is least squares on the two pieces alone.
TEST_F(TimeGapCommands, OrdersReportTheGapAndFillItUnderMissing) {
  const std::string grid = " --output y --input u --na 1:2 --nb 1:2 --nk 1 --split 1 --detrend none --json";
  const nlohmann::json reported = CommandJson("orders " + path + grid);
  ExpectOneTimeGap(reported, 0);
  EXPECT_EQ(reported["samples"], 400 - 2);  // not filled: the rows are taken as consecutive
  const nlohmann::json filled = CommandJson("orders " + path + grid + " --missing");
  ExpectOneTimeGap(filled, 3);
  EXPECT_EQ(filled["samples"], 198 + 198);
  for (const nlohmann::json& s : filled["structures"]) {
    const PieceFit ls = PieceLeastSquares(pieces, s["na"], s["nb"], 1, 2);
    EXPECT_NEAR(s["loss"].get<double>(), ls.loss, 1e-10 * ls.loss);
  }
}

TEST_F(TimeGapCommands, CompareAndPredictReportTheGapAndFillItUnderMissing) {
  const std::string options = kArx221 + " --split 1 --detrend none --outliers none --estimators rls --json";
  ExpectOneTimeGap(CommandJson("compare " + path + options), 0);
  const nlohmann::json filled = CommandJson("compare " + path + options + " --missing");
  ExpectOneTimeGap(filled, 3);
  const PieceFit ls = PieceLeastSquares(pieces, 2, 2, 1, 2);
  const std::vector<double> theta = filled["reference"]["theta"];
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(theta[static_cast<std::size_t>(i)], ls.theta(i), 1e-9) << i;

  const std::string model = TempDir() + "/gap_model.json";
  ASSERT_EQ(RunCli("fit " + path + kArx221 + " --split 1 --detrend none --missing --save " + model).exit_code, 0);
  const nlohmann::json p = CommandJson("predict " + model + " " + path + " --missing --json");
  ExpectOneTimeGap(p, 3);
  EXPECT_EQ(p["samples"], 198 + 198);
  EXPECT_EQ(p["rows"], nlohmann::json::array({1, 403}));
  // Without --missing the CSV stays CSV: the gap is reported on stderr.
  const CliResult csv = RunCli("predict " + model + " " + path);
  ASSERT_EQ(csv.exit_code, 0) << csv.err;
  EXPECT_NE(csv.err.find("time column 't': 1 gap"), std::string::npos) << csv.err;
  EXPECT_EQ(csv.out.rfind("row,y,one_step,residual\n", 0), 0u);
}

// ident stream compares each step with the median of the recent ones: the gap is reported on stderr, or filled
// under --missing, after which RLS ends at least squares on the two pieces alone.
TEST_F(TimeGapCommands, StreamReportsTheGapAndFillsItUnderMissing) {
  const std::string arx = kArx221 + " --estimator rls";
  const CliResult reported = RunCli("stream " + path + arx);
  ASSERT_EQ(reported.exit_code, 0) << reported.err;
  EXPECT_EQ(JsonLines(reported.out).size(), 400u);
  EXPECT_NE(reported.err.find("time column 't': gap at data row 201 (19.9 -> 20.3, 3 samples missing"),
            std::string::npos)
      << reported.err;
  const CliResult filled = RunCli("stream " + path + arx + " --missing");
  ASSERT_EQ(filled.exit_code, 0) << filled.err;
  EXPECT_EQ(filled.err, "");
  const std::vector<nlohmann::json> lines = JsonLines(filled.out);
  ASSERT_EQ(lines.size(), 403u);
  // The three filled rows and the two whose regressors reach back into them have no update.
  for (std::size_t row = 201; row <= 205; ++row) EXPECT_EQ(lines[row - 1]["status"], "missing") << row;
  EXPECT_EQ(lines[205]["status"], "ok");
  const PieceFit ls = PieceLeastSquares(pieces, 2, 2, 1, 2);
  const std::vector<double> theta = lines.back()["theta"];
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(theta[static_cast<std::size_t>(i)], ls.theta(i), 1e-8) << i;

  const std::string back = WriteFile("back_t.csv", "t,u,y\n0,1,2\n1,2,3\n0.5,3,4\n");
  const CliResult error = RunCli("stream " + back + arx);
  EXPECT_EQ(error.exit_code, 1);
  EXPECT_NE(error.err.find("back_t.csv:4: time column 't' does not increase: 0.5 after 1"), std::string::npos)
      << error.err;
}

}  // namespace
}  // namespace ident::testing
