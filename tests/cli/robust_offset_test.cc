// The operating point of a robust fit: the output's mean after a Hampel filter (workflow/spike_robust_mean.h)
// against the plain mean on clean signals, against spikes of any size, and through `ident fit`/`compare`
// on a record whose outliers would move the plain mean by many noise scales.
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "ident/workflow/spike_robust_mean.h"
#include "tests/support/cli.h"
#include "tests/support/test_data.h"

namespace ident::workflow {
namespace {

// A slow sinusoid in Gaussian noise, N samples.
Eigen::VectorXd NoisySine(int n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0, 0.05);
  Eigen::VectorXd y(n);
  for (int t = 0; t < n; ++t) y(t) = 3 + std::sin(0.02 * t) + noise(rng);
  return y;
}

TEST(SpikeRobustMean, IsThePlainMeanOfASignalWithoutSpikes) {
  const Eigen::VectorXd y = NoisySine(2000, 5);
  EXPECT_NEAR(SpikeRobustMean(y), y.mean(), 1e-12);
  // A step (two plateaus, quantised: most deviations from the running median are exactly zero).
  Eigen::VectorXd step = Eigen::VectorXd::Constant(300, 1.0);
  step.tail(100).setConstant(4.0);
  EXPECT_NEAR(SpikeRobustMean(step), step.mean(), 1e-12);
  EXPECT_EQ(SpikeRobustMean(Eigen::VectorXd::Constant(7, 2.5)), 2.5);
}

// Once a spike is gross its size no longer enters: 5 % spikes of ±10 and of ±1e6 (the same rows and
// signs) give the same offset, within a tenth of the noise std of the clean signal's mean, where the
// plain mean moves by thousands.
TEST(SpikeRobustMean, SpikesOfAnySizeLeaveTheOffset) {
  const Eigen::VectorXd clean = NoisySine(1000, 9);
  std::mt19937_64 rng(3);
  std::vector<int> rows;
  for (int t = 0; t < 1000; ++t)
    if (std::uniform_real_distribution<double>(0, 1)(rng) < 0.05) rows.push_back(t);
  auto spiked = [&](double size) {
    Eigen::VectorXd y = clean;
    for (std::size_t i = 0; i < rows.size(); ++i) y(rows[i]) += (i % 3 == 0 ? -size : size);
    return y;
  };
  const double small = SpikeRobustMean(spiked(10)), large = SpikeRobustMean(spiked(1e6));
  EXPECT_EQ(small, large);
  EXPECT_NEAR(large, clean.mean(), 0.005);
  EXPECT_GT(std::abs(spiked(1e6).mean() - clean.mean()), 1000);
}

// A cluster of five same-signed spikes in nine samples fills more than half of the window around its
// middle; once its edges are flagged and out, the rest is found too.
TEST(SpikeRobustMean, FindsAClusterOfSpikes) {
  const Eigen::VectorXd clean = NoisySine(1000, 4);
  Eigen::VectorXd y = clean;
  for (int t : {500, 504, 505, 506, 508}) y(t) += 1000;
  EXPECT_NEAR(SpikeRobustMean(y), clean.mean(), 0.005);
}

TEST(SpikeRobustMean, SkipsMissingSamples) {
  Eigen::VectorXd y = NoisySine(500, 2);
  const double mean = y.mean();
  Eigen::VectorXd with_gaps(502);
  with_gaps << std::numeric_limits<double>::quiet_NaN(), y.head(250), std::numeric_limits<double>::quiet_NaN(),
      y.tail(250);
  EXPECT_NEAR(SpikeRobustMean(with_gaps), mean, 1e-3);
  EXPECT_EQ(SpikeRobustMean(Eigen::VectorXd::Constant(3, std::numeric_limits<double>::quiet_NaN())), 0);
}

nlohmann::json Json(const std::string& args) {
  const testing::CliResult r = testing::RunCli(args + " --json");
  EXPECT_EQ(r.exit_code, 0) << args << "\n" << r.err;
  return r.exit_code == 0 ? nlohmann::json::parse(r.out) : nlohmann::json();
}

// gas_furnace (148 estimation rows), 5 % output outliers: at 1000σ the plain mean of y moves by several
// noise scales, which a model without intercept absorbs as a constant bias. `compare` detrends each
// estimator's corrupted record as `fit` does: the Cauchy estimator's median θ distance at 1000σ is no larger
// than at 20σ (+0.01), its offset stays within 0.1σ of the clean mean, least squares' offset does not.
TEST(RobustOffset, OutlierSizeDoesNotEnterThroughTheDetrending) {
  auto run = [](double size) {
    return Json(fmt::format("compare gas_furnace --estimators cauchy,rls --trials 12 --outliers 0.05:{}:1", size));
  };
  const nlohmann::json at20 = run(20), at1000 = run(1000);
  const double sigma = at1000["outliers"]["sigma"], clean_mean = 52.41621621621622;  // y over rows 1-148
  auto of = [](const nlohmann::json& j, const std::string& name) {
    for (const auto& e : j["estimators"])
      if (e["estimator"] == name) return e;
    return nlohmann::json();
  };
  const double small = of(at20, "cauchy")["spread"]["theta_distance"]["median"];
  const double large = of(at1000, "cauchy")["spread"]["theta_distance"]["median"];
  std::printf("[ measured ] gas_furnace 5 %%: cauchy θ distance median %.3f at 20σ, %.3f at 1000σ\n", small, large);
  EXPECT_LE(large, small + 0.01);
  EXPECT_LT(large, 0.1);
  EXPECT_LT(std::abs(of(at1000, "cauchy")["output_offset"].get<double>() - clean_mean), 0.1 * sigma);
  EXPECT_GT(std::abs(of(at1000, "rls")["output_offset"].get<double>() - clean_mean), 1 * sigma);
}

// `ident fit` on a file with the outliers in it reports the filtered offset in detrend_means and lands near
// the clean fit; with --estimator rls the plain mean.
TEST(RobustOffset, FitReportsTheFilteredOffset) {
  const std::string path = ident::testing::TempDir() + "/gas_furnace_spiked.csv";
  std::FILE* in = std::fopen(testing::DatasetPath("gas_furnace.csv").c_str(), "r");
  ASSERT_NE(in, nullptr);
  std::FILE* out = std::fopen(path.c_str(), "w");
  char line[256];
  for (int row = -1; std::fgets(line, sizeof line, in); ++row) {
    double t, u, y;
    if (row >= 0 && row < 148 && row % 20 == 7 && std::sscanf(line, "%lf,%lf,%lf", &t, &u, &y) == 3)
      std::fprintf(out, "%.17g,%.17g,%.17g\n", t, u, y + 100.0);
    else
      std::fputs(line, out);
  }
  std::fclose(in);
  std::fclose(out);
  const std::string structure = "--output y --input u --na 2 --nb 2 --nk 3";
  const nlohmann::json robust = Json(fmt::format("fit {} {} --estimator cauchy", path, structure));
  const nlohmann::json ls = Json(fmt::format("fit {} {} --estimator rls", path, structure));
  const nlohmann::json clean = Json(fmt::format("fit gas_furnace {} --estimator cauchy", structure));
  EXPECT_NEAR(robust["detrend_means"]["y"].get<double>(), 52.41621621621622, 0.02);
  EXPECT_NEAR(ls["detrend_means"]["y"].get<double>(), 52.41621621621622 + 8 * 100.0 / 148, 1e-9);
  double distance = 0, norm = 0;
  for (int i = 0; i < 4; ++i) {
    distance += std::pow(robust["theta"][i].get<double>() - clean["theta"][i].get<double>(), 2);
    norm += std::pow(clean["theta"][i].get<double>(), 2);
  }
  EXPECT_LT(std::sqrt(distance / norm), 0.1);
  std::remove(path.c_str());
}

}  // namespace
}  // namespace ident::workflow
