// Residual analysis (ident/workflow/residual_analysis.h) against closed forms, and the --plot options.
#include <cmath>
#include <filesystem>
#include <random>

#include <gtest/gtest.h>
#include <boost/math/distributions/chi_squared.hpp>
#include <nlohmann/json.hpp>

#include "ident/workflow/residual_analysis.h"
#include "tests/support/cli.h"

namespace ident::testing {
namespace {

TEST(ResidualAnalysis, CorrelationsMatchTheirDefinitionOnAHandExample) {
  // e = [1, −1, 2, 0] (mean 0.5): centred c = [0.5, −1.5, 1.5, −0.5], Σc² = 5;
  // r(1) = (0.5·−1.5 + −1.5·1.5 + 1.5·−0.5)/5 = −3.75/5 = −0.75.
  const std::vector<double> r = workflow::Autocorrelation({1, -1, 2, 0}, 2);
  EXPECT_DOUBLE_EQ(r[0], -0.75);
  EXPECT_DOUBLE_EQ(r[1], (0.5 * 1.5 + -1.5 * -0.5) / 5);
  const std::vector<double> x = workflow::CrossCorrelation({1, -1, 2, 0}, {1, -1, 2, 0}, 0);
  EXPECT_DOUBLE_EQ(x[0], 1.0);
}

TEST(ResidualAnalysis, AnAr1SequenceHasLagOneCorrelationNearItsCoefficient) {
  // e(t) = 0.6 e(t−1) + w(t): r(τ) → 0.6^τ; with N = 20000 the sampling sd is ≈ 0.006.
  std::mt19937_64 rng(3);
  std::normal_distribution<double> w(0, 1);
  std::vector<double> e{0};
  for (int t = 1; t < 20000; ++t) e.push_back(0.6 * e.back() + w(rng));
  const std::vector<double> r = workflow::Autocorrelation(e, 3);
  EXPECT_NEAR(r[0], 0.6, 0.03);
  EXPECT_NEAR(r[1], 0.36, 0.03);
  EXPECT_NEAR(r[2], 0.216, 0.03);
}

TEST(ResidualAnalysis, CrossCorrelationPeaksAtTheDelay) {
  std::mt19937_64 rng(5);
  std::normal_distribution<double> w(0, 1);
  std::vector<double> u, e;
  for (int t = 0; t < 5000; ++t) u.push_back(w(rng));
  for (int t = 0; t < 5000; ++t) e.push_back(t >= 3 ? u[static_cast<std::size_t>(t - 3)] : 0.0);
  const std::vector<double> r = workflow::CrossCorrelation(e, u, 6);
  EXPECT_NEAR(r[3], 1.0, 0.01);
  for (int k : {0, 1, 2, 4, 5, 6}) EXPECT_LT(std::abs(r[static_cast<std::size_t>(k)]), 0.06) << k;
}

TEST(ResidualAnalysis, WhiteNoiseFailsTheWhitenessTestAtAboutTheNominalRate) {
  // 400 seeded white sequences of N = 500: the 1 % portmanteau test rejects Binomial(400, 0.01)
  // times (≈ 4; P(> 14) < 1e-5, allowing for the χ² approximation at finite N).
  const double limit = boost::math::quantile(boost::math::chi_squared(20), 0.99);
  std::mt19937_64 rng(17);
  std::normal_distribution<double> w(0, 1);
  int rejected = 0;
  for (int s = 0; s < 400; ++s) {
    std::vector<double> e;
    for (int t = 0; t < 500; ++t) e.push_back(w(rng));
    double q = 0;
    for (double r : workflow::Autocorrelation(e, 20)) q += 500 * r * r;
    rejected += q > limit;
  }
  EXPECT_LE(rejected, 14);
}

TEST(FitReport, EndsWithTheResidualAnalysis) {
  const CliResult good = RunCli("fit dryer --output y --input u --na 2 --nb 2 --nk 3");
  ASSERT_EQ(good.exit_code, 0) << good.err;
  EXPECT_NE(good.out.find("residual analysis (validation one-step residuals, N = 496, 99 % band ±0.116)"),
            std::string::npos)
      << good.out;  // 2.58/√496 = 0.1158
  // A wrong delay (nk = 1 instead of 3) leaves the input in the residuals.
  const CliResult bad = RunCli("fit dryer --output y --input u --na 1 --nb 1 --nk 1");
  EXPECT_NE(bad.out.find("correlated with the input"), std::string::npos) << bad.out;
  const CliResult json = RunCli("fit dryer --output y --input u --na 1 --nb 1 --nk 1 --json");
  const nlohmann::json j = nlohmann::json::parse(json.out);
  EXPECT_EQ(j["residual_analysis"]["autocorrelation"].size(), 20u);
  EXPECT_EQ(j["residual_analysis"]["cross_correlation"]["u"].size(), 21u);
  EXPECT_EQ(j["residual_analysis"]["independent"], false);
}

TEST(Plots, FitAndCompareWriteNonEmptyImages) {
  for (const char* ext : {"svg", "png"}) {
    const std::string fit = TempDir() + "/fit." + ext, cmp = TempDir() + "/compare." + ext;
    const CliResult a = RunCli("fit dryer --output y --input u --na 2 --nb 2 --nk 3 --plot " + fit);
    ASSERT_EQ(a.exit_code, 0) << a.err;
    EXPECT_GT(std::filesystem::file_size(fit), 5000u);
    const CliResult b = RunCli("compare dryer --estimators rls --trials 3 --plot " + cmp);
    ASSERT_EQ(b.exit_code, 0) << b.err;
    EXPECT_GT(std::filesystem::file_size(cmp), 3000u);
  }
  const std::string svg = ReadFile(TempDir() + "/fit.svg");
  EXPECT_NE(svg.find("<svg"), std::string::npos);
  EXPECT_NE(svg.find("parameter trajectories"), std::string::npos);
}

TEST(Plots, BadPlotFileIsAClearError) {
  const CliResult r = RunCli("fit dryer --output y --input u --plot " + TempDir() + "/fit.bmp");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("fit.bmp"), std::string::npos) << r.err;
  const CliResult c = RunCli("compare dryer --estimators rls --plot /nonexistent/dir/c.png");
  EXPECT_EQ(c.exit_code, 1);
  EXPECT_NE(c.err.find("c.png"), std::string::npos) << c.err;
}

}  // namespace
}  // namespace ident::testing
