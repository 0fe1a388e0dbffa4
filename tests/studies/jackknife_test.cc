// The jackknife standard error of a ratio of sums (studies/mems/jackknife.h), which the MEMS study prints beside
// each calibration: against its closed form for two groups, and against the sampling spread of the ratio
// over seeded Monte Carlo replicates of independent groups.
#include "studies/mems/jackknife.h"

#include <array>
#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>

namespace ident {
namespace {

TEST(Jackknife, TwoGroupsGiveHalfTheDifferenceOfTheGroupRatios) {
  // R_(1) = a2/c2, R_(2) = a1/c1: se² = (1/2)·2·(d/2)² with d = a1/c1 − a2/c2.
  const std::array<double, 2> a{3.0, 5.0}, c{2.0, 7.0};
  EXPECT_NEAR(JackknifeRatioStandardError(a, c), std::abs(3.0 / 2.0 - 5.0 / 7.0) / 2, 1e-15);
}

TEST(Jackknife, ProportionalGroupsHaveNoSpread) {
  const std::array<double, 5> c{1.0, 2.5, 0.3, 4.0, 7.0};
  std::array<double, 5> a{};
  for (int b = 0; b < 5; ++b) a[b] = 1.7 * c[b];
  EXPECT_LT(JackknifeRatioStandardError(a, c), 1e-15);
}

TEST(Jackknife, MatchesTheSpreadOfTheRatioOverIndependentReplicates) {
  // Ten independent groups per replicate, as the study's blocks: c = sum of squared errors (gamma), a =
  // predicted variance correlated with c. The jackknife's mean over replicates estimates the ratio's
  // standard deviation; 4000 replicates pin that down to ≈ 1.1 %, the jackknife's own bias at ten groups is
  // a few per cent (0.99 here).
  std::mt19937_64 rng(20261126);
  std::gamma_distribution<double> err2(2.0, 1.0), extra(4.0, 0.25);
  constexpr int kReplicates = 4000, kGroups = 10;
  std::vector<double> ratios;
  double mean_se = 0;
  for (int r = 0; r < kReplicates; ++r) {
    std::array<double, kGroups> a{}, c{};
    for (int b = 0; b < kGroups; ++b) {
      c[b] = err2(rng);
      a[b] = 0.5 * c[b] + extra(rng);
    }
    double sa = 0, sc = 0;
    for (int b = 0; b < kGroups; ++b) sa += a[b], sc += c[b];
    ratios.push_back(sa / sc);
    mean_se += JackknifeRatioStandardError(a, c) / kReplicates;
  }
  double mean = 0, var = 0;
  for (double x : ratios) mean += x / kReplicates;
  for (double x : ratios) var += (x - mean) * (x - mean) / (kReplicates - 1);
  const double sd = std::sqrt(var);
  EXPECT_GT(sd, 0.05);  // a spread worth estimating
  EXPECT_NEAR(mean_se / sd, 1.0, 0.06) << "jackknife " << mean_se << ", replicate spread " << sd;
}

}  // namespace
}  // namespace ident
