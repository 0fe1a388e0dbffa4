// Model structures through `ident fit`: MISO ARX, one output of a MIMO record at a time, FIR and
// static regression, each against an independent reference (datasets/README.md baselines computed
// with numpy/R, or exact synthetic laws).
#include <cmath>

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "tests/support/cli.h"

namespace ident::testing {
namespace {

nlohmann::json StructureFitJson(const std::string& args) {
  const CliResult r = RunCli("fit " + args + " --json");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  return nlohmann::json::parse(r.out);
}

TEST(Structures, MisoArxOnCdPlayerArmReproducesTheReadmeBaselinesForBothOutputs) {
  const nlohmann::json y1 = StructureFitJson("cd_player_arm --output y1 --input u1,u2 --na 2 --nb 2,2 --nk 1,1");
  EXPECT_EQ(y1["structure"], "ARX(2,[2,2],[1,1])");
  EXPECT_EQ(y1["parameter_names"], (std::vector<std::string>{"a1", "a2", "b1_1", "b2_1", "b1_2", "b2_2"}));
  EXPECT_NEAR(y1["fit_percent"]["one_step"].get<double>(), 83.10, 0.005);
  EXPECT_NEAR(y1["fit_percent"]["simulation"].get<double>(), 66.72, 0.005);
  const nlohmann::json y2 = StructureFitJson("cd_player_arm --output y2 --input u1,u2 --na 2 --nb 2 --nk 1");
  EXPECT_NEAR(y2["fit_percent"]["one_step"].get<double>(), 77.04, 0.005);
  EXPECT_NEAR(y2["fit_percent"]["simulation"].get<double>(), 76.88, 0.005);
}

TEST(Structures, MisoArxWithThreeInputsOnGlassFurnace) {
  // README: rows 1-748 estimate, 749-1247 validate (split 0.6), MISO ARX(2,[2,2,2]), nk = 1.
  const std::vector<double> readme = {74.01, 77.49, 77.18, 33.30, 82.96, 81.59};
  for (int k = 1; k <= 6; ++k) {
    const nlohmann::json j =
        StructureFitJson("glassfurnace --output y" + std::to_string(k) + " --input u1,u2,u3 --nb 2 --nk 1 --split 0.6");
    EXPECT_EQ(j["samples_estimation"], 748);
    EXPECT_NEAR(j["fit_percent"]["one_step"].get<double>(), readme[static_cast<std::size_t>(k - 1)], 0.005) << k;
  }
}

TEST(Structures, MisoWithDifferentDelaysPerInputRecoversAnExactLaw) {
  // y(t) = 0.5 y(t−1) + 1.0 u1(t−1) − 0.4 u2(t−3) + 0.2 u2(t−4), no noise: θ exact.
  std::string csv = "u1,u2,y\n";
  std::vector<double> u1, u2, y;
  for (int t = 0; t < 120; ++t) {
    u1.push_back(std::sin(0.7 * t) + std::cos(0.13 * t * t));
    u2.push_back(std::cos(1.3 * t) - 0.5 * std::sin(0.029 * t * t));
    double v = 0;
    if (t >= 4) v = 0.5 * y[t - 1] + 1.0 * u1[t - 1] - 0.4 * u2[t - 3] + 0.2 * u2[t - 4];
    y.push_back(v);
    csv += fmt::format("{:.17g},{:.17g},{:.17g}\n", u1[t], u2[t], v);
  }
  const std::string path = WriteFile("miso.csv", csv);
  const nlohmann::json j = StructureFitJson(path + " --output y --input u1,u2 --na 1 --nb 1,2 --nk 1,3 --detrend none");
  EXPECT_EQ(j["structure"], "ARX(1,[1,2],[1,3])");
  const std::vector<double> theta = j["theta"], expected = {-0.5, 1.0, -0.4, 0.2};
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(theta[i], expected[i], 1e-8) << i;
}

TEST(Structures, RlsNeverFlagsSoCleaningLeavesItsFitUnchanged) {
  const std::string args = "dryer --output y --input u --na 2 --nb 2 --nk 3";
  const nlohmann::json on = StructureFitJson(args), off = StructureFitJson(args + " --clean-regressors off");
  EXPECT_EQ(on["cleaned"], 0);
  EXPECT_EQ(on["theta"], off["theta"]);
}

TEST(Structures, FirModelIsArxWithNaZero) {
  std::string csv = "u,y\n";
  std::vector<double> u;
  for (int t = 0; t < 80; ++t) {
    u.push_back(std::sin(0.9 * t) + 0.3 * std::cos(0.31 * t * t));
    const double y = t >= 3 ? 0.7 * u[t - 2] - 0.2 * u[t - 3] : 0;
    csv += fmt::format("{:.17g},{:.17g}\n", u[t], y);
  }
  const nlohmann::json j =
      StructureFitJson(WriteFile("fir.csv", csv) + " --output y --input u --na 0 --nb 2 --nk 2 --detrend none");
  EXPECT_EQ(j["structure"], "FIR(0,2,2)");
  EXPECT_NEAR(j["theta"][0].get<double>(), 0.7, 1e-9);
  EXPECT_NEAR(j["theta"][1].get<double>(), -0.2, 1e-9);
  EXPECT_NEAR(j["fit_percent"]["one_step"].get<double>(), 100, 1e-6);
}

TEST(Structures, StaticRegressionOnStacklossMatchesROls) {
  // datasets/README.md: R lm(stack_loss ~ air_flow + water_temp + acid_conc).
  const nlohmann::json j = StructureFitJson(
      "stackloss --output stack_loss --regressors air_flow,water_temp,acid_conc "
      "--intercept --split 1");
  const std::vector<double> theta = j["theta"], r_lm = {-39.920, 0.71564, 1.2953, -0.15212};
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(theta[i], r_lm[i], 5e-4 * std::abs(r_lm[i]) + 5e-4) << i;
  const nlohmann::json t = StructureFitJson("telef --output calls --regressors year --intercept --split 1");
  EXPECT_NEAR(t["theta"][0].get<double>(), -983.89, 0.01);
  EXPECT_NEAR(t["theta"][1].get<double>(), 0.50415, 1e-5);
}

}  // namespace
}  // namespace ident::testing
