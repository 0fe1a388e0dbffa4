// `ident fit --save` and `ident predict`: the saved model reproduces the fit's validation figures exactly,
// k-step predictions against an explicit ARX recursion, physical units, the model file's round trip and
// bad input.
#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "ident/io/csv.h"
#include "ident/workflow/saved_model.h"
#include "tests/support/cli.h"
#include "tests/support/test_data.h"

namespace ident::testing {
namespace {

nlohmann::json Json(const std::string& args) {
  const CliResult r = RunCli(args);
  EXPECT_EQ(r.exit_code, 0) << args << ": " << r.err;
  return nlohmann::json::parse(r.out);
}

TEST(Predict, ReproducesTheFitsValidationFiguresExactly) {
  const std::string dir = TempDir();
  for (const std::string& fit : {
           std::string("dryer --output y --input u --na 2 --nb 2 --nk 3 --estimator cauchy"),
           std::string("gas_furnace --output y --input u --na 2 --nb 2 --nk 3 --estimator rls --split 0.7"),
           std::string("stackloss --output stack_loss --regressors air_flow,water_temp,acid_conc --intercept "
                       "--split 1 --estimator huber"),
       }) {
    const std::string model = dir + "/model.json";
    const nlohmann::json f = Json("fit " + fit + " --save " + model + " --json");
    const workflow::SavedModel m = workflow::SavedModel::Read(model);
    const std::string rows =
        std::to_string(m.validation.first + 1) + ":" + std::to_string(m.validation.first + m.validation.count);
    const nlohmann::json p =
        Json("predict " + model + " " + fit.substr(0, fit.find(' ')) + " --rows " + rows + " --json");
    EXPECT_EQ(p["fit_percent"], f["fit_percent"]) << fit;  // bit for bit
    EXPECT_EQ(p["rms"], f["rms"]) << fit;
    for (std::size_t i = 0; i < f["theta"].size(); ++i) EXPECT_EQ(m.theta(static_cast<Eigen::Index>(i)), f["theta"][i]);
    EXPECT_EQ(m.covariance.rows(), m.theta.size());
    EXPECT_EQ(m.data_checksum.size(), 16u);
  }
}

TEST(Predict, KStepPredictionsFollowTheArxRecursionInPhysicalUnits) {
  const std::string dir = TempDir();
  const std::string model = dir + "/dryer.json";
  ASSERT_EQ(RunCli("fit dryer --output y --input u --na 2 --nb 2 --nk 3 --save " + model).exit_code, 0);
  const workflow::SavedModel m = workflow::SavedModel::Read(model);
  const CliResult r = RunCli("predict " + model + " dryer --rows 601:700 --horizon 2 --simulate");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const io::DataTable out = io::ParseCsv(r.out, "predict", {.missing_as_nan = true});
  ASSERT_EQ(out.names, (std::vector<std::string>{"row", "y", "one_step", "residual", "k2_step", "simulation"}));
  // The recursion written out: detrended data, a = θ(0..1), b = θ(2..3), delay 3.
  const io::DataTable data = io::ReadCsv(DatasetPath("dryer.csv"));
  double my = 0, mu = 0;
  for (const auto& [name, mean] : m.detrend_means) (name == "y" ? my : mu) = mean;
  auto y = [&](int t) { return data.values(t, 2) - my; };
  auto u = [&](int t) { return data.values(t, 1) - mu; };
  const Eigen::VectorXd& th = m.theta;
  auto predict = [&](int t, double y1, double y2) {
    return -th(0) * y1 - th(1) * y2 + th(2) * u(t - 3) + th(3) * u(t - 4);
  };
  for (int i = 4; i < out.num_rows(); ++i) {  // t0 = 4 rows of the segment have no regressor
    const int t = 600 + i;
    const double one = predict(t, y(t - 1), y(t - 2));
    const double two = i >= 5 ? predict(t, predict(t - 1, y(t - 2), y(t - 3)), y(t - 2)) : one;
    EXPECT_NEAR(out.values(i, 2), one + my, 1e-12) << t;
    EXPECT_NEAR(out.values(i, 4), two + my, 1e-12) << t;
    EXPECT_NEAR(out.values(i, 3), out.values(i, 1) - out.values(i, 2), 1e-12) << t;
    EXPECT_EQ(out.values(i, 1), data.values(t, 2));  // the measured output as recorded
  }
  for (int i = 0; i < 4; ++i) EXPECT_TRUE(std::isnan(out.values(i, 2)));
  // A horizon beyond the segment is the simulation.
  const CliResult sim = RunCli("predict " + model + " dryer --rows 601:700 --horizon 1000 --simulate");
  const io::DataTable s = io::ParseCsv(sim.out, "predict", {.missing_as_nan = true});
  for (int i = 4; i < s.num_rows(); ++i) EXPECT_NEAR(s.values(i, 4), s.values(i, 5), 1e-9) << i;
}

TEST(SavedModel, ReadsBackWhatItWrites) {
  workflow::SavedModel m;
  m.model.output = "y";
  m.model.inputs = {"u1", "u2"};
  m.model.na = 1;
  m.model.nb = {2, 1};
  m.model.nk = {1, 3};
  m.structure_name = "ARX(1,[2,1],[1,3])";
  m.parameter_names = {"a1", "b1_1", "b2_1", "b1_2"};
  m.theta = Eigen::Vector4d(0.1, -1.0 / 3.0, 2e-300, 1e300);
  m.theta_std = Eigen::Vector4d(1, 2, 3, 4);
  m.covariance = Eigen::Matrix4d::Identity() / 7.0;
  m.detrend_means = {{"y", 1.0 / 3.0}, {"u1", -2.5}};
  m.estimator = "cauchy";
  m.kind = "recursive";
  m.validation = {10, 20};
  m.validation_scores.one_step = 91.25;
  const workflow::SavedModel back =
      workflow::SavedModel::FromJson(nlohmann::json::parse(m.ToJson().dump()), "round trip");
  EXPECT_EQ(back.theta, m.theta);
  EXPECT_EQ(back.model.nb, m.model.nb);
  EXPECT_EQ(back.model.nk, m.model.nk);
  auto sorted = [](auto v) {
    std::sort(v.begin(), v.end());
    return v;
  };
  EXPECT_EQ(sorted(back.detrend_means), sorted(m.detrend_means));
  EXPECT_EQ(back.validation.first, 10);
  EXPECT_EQ(back.validation.count, 20);
  EXPECT_EQ(nlohmann::json::parse(back.ToJson().dump()), nlohmann::json::parse(m.ToJson().dump()));
}

TEST(Predict, BadInputExitsOneWithOneLine) {
  const std::string dir = TempDir();
  const std::string model = dir + "/m.json";
  ASSERT_EQ(RunCli("fit dryer --output y --input u --na 2 --nb 2 --nk 3 --save " + model).exit_code, 0);
  const std::string other = WriteFile("other.json", "{\"nu0\": 1}");
  const std::string cols = WriteFile("cols.csv", "a,b\n1,2\n3,4\n");
  for (const auto& [args, message] : std::vector<std::pair<std::string, std::string>>{
           {"predict " + dir + "/missing.json dryer", "cannot open model file"},
           {"predict " + other + " dryer", "not an ident model"},
           {"predict " + model + " " + cols, "no column"},
           {"predict " + model + " dryer --rows 0:10", "has rows 1-1000"},
           {"predict " + model + " dryer --rows 1:3", "too few"},
           {"predict " + model + " dryer --horizon 0", "--horizon 0"},
       }) {
    const CliResult r = RunCli(args);
    EXPECT_EQ(r.exit_code, 1) << args;
    EXPECT_NE(r.err.find(message), std::string::npos) << args << ": " << r.err;
  }
}

}  // namespace
}  // namespace ident::testing

namespace ident::testing {
namespace {

TEST(Predict, AnUnstableModelIsReportedWithTheRowWhereItsSimulationDiverged) {
  const std::string dir = TempDir();
  const std::string model = dir + "/stable.json";
  ASSERT_EQ(RunCli("fit dryer --output y --input u --na 2 --nb 2 --nk 3 --save " + model).exit_code, 0);
  nlohmann::json m = nlohmann::json::parse(ReadFile(model));
  const nlohmann::json stable = Json("predict " + model + " dryer --rows 501:1000 --json");
  EXPECT_TRUE(stable["simulation_diverged_at"].is_null());
  EXPECT_TRUE(stable["fit_percent"]["simulation"].is_number());
  // A(q) = 1 − 2.5 q⁻¹ + 1.2 q⁻²: poles 1.87 and 0.64, one outside the unit circle.
  m["theta"] = {-2.5, 1.2, 0.06, 0.05};
  const std::string unstable = WriteFile("unstable.json", m.dump());
  const nlohmann::json j = Json("predict " + unstable + " dryer --rows 501:1000 --json");
  EXPECT_TRUE(j["fit_percent"]["simulation"].is_null());
  EXPECT_TRUE(j["rms"]["simulation"].is_null());
  const int row = j["simulation_diverged_at"].get<int>();
  EXPECT_GT(row, 504);  // after the first t0 = 4 rows of the segment, which are measured
  EXPECT_LT(row, 600);  // 1.87ⁿ passes 1000 within a few dozen samples
  EXPECT_TRUE(j["fit_percent"]["one_step"].is_number());  // the one-step predictor is still scored
}

}  // namespace
}  // namespace ident::testing

namespace ident::testing {
namespace {

TEST(Validate, ASeparateRecordIsScoredAsPredictScoresIt) {
  const std::string arx = " --output y --input u --na 2 --nb 2 --nk 1";
  const std::string model = TempDir() + "/tanks.json";
  const nlohmann::json f =
      Json("fit cascaded_tanks_estimation" + arx + " --validate cascaded_tanks_validation --save " + model + " --json");
  EXPECT_EQ(f["split"], 1.0);  // all of the estimation record estimates
  EXPECT_EQ(f["samples_estimation"], 1024);
  EXPECT_EQ(f["samples_validation"], 1024);
  EXPECT_NE(f["validation_data"].get<std::string>().find("cascaded_tanks_validation"), std::string::npos);
  EXPECT_TRUE(f["residual_analysis"].is_object());
  const nlohmann::json p = Json("predict " + model + " cascaded_tanks_validation --json");
  EXPECT_EQ(p["fit_percent"], f["fit_percent"]);
  EXPECT_EQ(p["rms"], f["rms"]);
  // Without --validate the same fit validates on its own rows, with other figures.
  const nlohmann::json own = Json("fit cascaded_tanks_estimation" + arx + " --split 1 --json");
  EXPECT_EQ(own["theta"], f["theta"]);
  EXPECT_TRUE(own["validation_data"].is_null());
  EXPECT_NE(own["fit_percent"], f["fit_percent"]);
  const CliResult bad = RunCli("fit cascaded_tanks_estimation" + arx + " --validate stackloss");
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_NE(bad.err.find("no column"), std::string::npos) << bad.err;
}

}  // namespace
}  // namespace ident::testing

namespace ident::testing {
namespace {

TEST(FitDefaults, ABundledRecordWithoutStructureOptionsTakesCompareSuggestion) {
  EXPECT_EQ(Json("fit dryer --json"), Json("fit dryer --output y --input u --na 2 --nb 2 --nk 3 --json"));
  const nlohmann::json s = Json("fit stackloss --json");
  EXPECT_EQ(s["structure"], "static(air_flow,water_temp,acid_conc)+intercept");
  EXPECT_EQ(s["split"], 1.0);
  EXPECT_EQ(s["detrend"], "none");
  nlohmann::json c = Json("compare stackloss --estimators rls --outliers none --json");
  EXPECT_EQ(c["structure"], s["structure"]);
  EXPECT_EQ(RunCli("fit dryer --input u").exit_code, 2);  // a structure option given: --output is needed
}

}  // namespace
}  // namespace ident::testing
