// Log-concave density MLE (ident/density/logconcave_mle.h): the characterisation (KKT) conditions of
// Dümbgen, Hüsler & Rufibach, closed-form cases, and golden values from R's logcondens produced by
// tests/density/data/logcondens_golden.R (committed beside its output; R is not needed to run this test).
#include "ident/density/logconcave_mle.h"

#include <cmath>
#include <fstream>
#include <map>
#include <random>
#include <sstream>

#include <gtest/gtest.h>

#include "common/error.h"
#include "tests/support/test_data.h"

namespace ident::approx {
namespace {

const std::string kData = std::string(IDENT_SOURCE_DIR) + "/tests/density/data/";

void ExpectKkt(const LogConcaveMle& mle, const std::string& label) {
  const LogConcaveKkt k = CheckKkt(mle);
  EXPECT_LE(k.max_directional_derivative, 1e-8) << label;
  EXPECT_LE(k.max_knot_residual, 1e-8) << label;
  EXPECT_LE(k.mass_error, 1e-8) << label;
  EXPECT_LE(k.max_concavity_violation, 1e-8) << label;
}

TEST(LogConcaveMle, TwoPointsGiveTheUniformDensity) {
  const LogConcaveMle mle = FitLogConcaveMle({1.0, 3.0, 3.0, 1.0});
  ASSERT_EQ(mle.knots.size(), 2);
  EXPECT_NEAR(mle.knot_phi(0), -std::log(2.0), 1e-12);
  EXPECT_NEAR(mle.knot_phi(1), -std::log(2.0), 1e-12);
  EXPECT_NEAR(mle.loglik, -4 * std::log(2.0), 1e-12);
  EXPECT_NEAR(mle.Cdf(2.5), 0.75, 1e-12);
}

TEST(LogConcaveMle, SatisfiesItsCharacterisationOnRandomSamples) {
  std::mt19937 rng(17);
  std::normal_distribution<double> N(0, 1);
  std::exponential_distribution<double> E(1.0);
  std::uniform_real_distribution<double> U(0, 1);
  for (int trial = 0; trial < 12; ++trial) {
    const int n = 20 + 150 * trial;
    std::vector<double> x(n);
    for (double& v : x) v = trial % 3 == 0 ? N(rng) : trial % 3 == 1 ? E(rng) : U(rng) * U(rng);
    const LogConcaveMle mle = FitLogConcaveMle(x);
    ExpectKkt(mle, "trial " + std::to_string(trial));
    // Sanity of the read-outs: the CDF ends at 1 and the log-likelihood is the sum of log densities.
    EXPECT_NEAR(mle.Cdf(mle.x(mle.x.size() - 1)), 1.0, 1e-8);
    double loglik = 0;
    for (double v : x) loglik += mle.LogDensity(v);
    EXPECT_NEAR(mle.loglik, loglik, 1e-9 * std::abs(loglik));
  }
}

// The progress hook sees each round with the largest relative directional derivative, the last call below
// the tolerance (the KKT condition max D_j <= 0 up to it, checked directly), and changes nothing.
TEST(LogConcaveMle, OnIterationSeesEachRoundAndEndsBelowTheTolerance) {
  std::mt19937 rng(3);
  std::normal_distribution<double> N(0, 1);
  std::vector<double> x(3000);
  for (double& v : x) v = N(rng);
  std::vector<std::pair<int, double>> calls;
  LogConcaveMleOptions options;
  options.on_iteration = [&calls](int round, double d) { calls.emplace_back(round, d); };
  const LogConcaveMle with = FitLogConcaveMle(x, options), without = FitLogConcaveMle(x);
  ASSERT_GE(calls.size(), 3u);
  EXPECT_EQ(calls.front().first, 0);
  EXPECT_GT(calls.front().second, 1e-3);  // the start (a few knots) is far from the optimum
  EXPECT_LE(calls.back().second, options.tolerance);
  const LogConcaveKkt kkt = CheckKkt(with);
  EXPECT_LE(kkt.max_directional_derivative, 1e-8);
  EXPECT_EQ(with.loglik, without.loglik);
  EXPECT_EQ(with.iterations, without.iterations);
}

TEST(LogConcaveMle, ConjugateOfTheNegativeLogDensityEqualsItsSupByNumericalMaximisation) {
  std::mt19937 rng(4);
  std::normal_distribution<double> N(0, 1);
  std::vector<double> x(100);
  for (double& v : x) v = N(rng);
  const LogConcaveMle mle = FitLogConcaveMle(x);
  const models::Penalty g = mle.NegativeLogDensity();
  for (double v : {-3.0, -0.7, 0.0, 0.4, 2.5}) {
    double a = mle.knots(0), b = mle.knots(mle.knots.size() - 1);
    auto fn = [&](double r) { return v * r + mle.LogDensity(r); };  // v r - g(r), concave
    for (int i = 0; i < 300; ++i) {
      const double m1 = a + (b - a) / 3, m2 = b - (b - a) / 3;
      if (fn(m1) < fn(m2))
        a = m1;
      else
        b = m2;
    }
    EXPECT_NEAR(mle.ConjugateOfNegativeLogDensity(v), fn(0.5 * (a + b)), 1e-10) << v;
    EXPECT_NEAR(g.Conjugate(Eigen::VectorXd::Constant(1, v)), mle.ConjugateOfNegativeLogDensity(v), 1e-12);
  }
}

TEST(LogConcaveMle, RejectsDegenerateSamples) {
  EXPECT_THROW(FitLogConcaveMle({2.0, 2.0, 2.0}), InvalidArgument);
  EXPECT_THROW(FitLogConcaveMle({1.0, std::nan(""), 2.0}), InvalidArgument);
}

std::vector<double> Column(const std::string& file, int col) {
  const Eigen::MatrixXd m = testing::ReadCsvMatrix(kData + file);
  std::vector<double> v(m.rows());
  for (int i = 0; i < m.rows(); ++i) v[i] = m(i, col);
  return v;
}

// summary.csv: name,n,loglik,L,knots
std::map<std::string, double> GoldenLoglik() {
  std::ifstream in(kData + "summary.csv");
  std::string line;
  std::getline(in, line);
  std::map<std::string, double> out;
  while (std::getline(in, line)) {
    std::stringstream ss(line);
    std::string name, n, loglik;
    std::getline(ss, name, ',');
    std::getline(ss, n, ',');
    std::getline(ss, loglik, ',');
    out[name] = std::stod(loglik);
  }
  return out;
}

TEST(LogConcaveMle, MatchesRLogcondensGoldenValues) {
  const std::map<std::string, double> golden = GoldenLoglik();
  ASSERT_EQ(golden.size(), 6u);
  for (const auto& [name, r_loglik] : golden) {
    const std::vector<double> samples = Column(name + "_samples.csv", 0);
    const LogConcaveMle mle = FitLogConcaveMle(samples);
    ExpectKkt(mle, name);
    // Never below logcondens' log-likelihood (it stops slightly short of the optimum).
    EXPECT_GE(mle.loglik, r_loglik - 1e-10 * std::abs(r_loglik)) << name;
    EXPECT_LE(mle.loglik, r_loglik + 1e-6 * std::abs(r_loglik)) << name;
    const std::vector<double> r_knots = Column(name + "_knots.csv", 0), r_phi = Column(name + "_knots.csv", 1);
    if (samples.size() <= 1000) {  // knots coincide for n <= 1000
      ASSERT_EQ(mle.knots.size(), static_cast<Eigen::Index>(r_knots.size())) << name;
      for (size_t a = 0; a < r_knots.size(); ++a) {
        EXPECT_EQ(mle.knots(a), r_knots[a]) << name << " knot " << a;
        EXPECT_NEAR(mle.knot_phi(a), r_phi[a], 2e-2) << name << " knot " << a;
      }
    }
    const std::vector<double> cx = Column(name + "_cdf.csv", 0), cF = Column(name + "_cdf.csv", 1);
    double max_cdf_difference = 0;
    for (size_t i = 0; i < cx.size(); ++i)
      max_cdf_difference = std::max(max_cdf_difference, std::abs(mle.Cdf(cx[i]) - cF[i]));
    EXPECT_LT(max_cdf_difference, 1e-4) << name;  // measured: <= 2.6e-5
  }
}

}  // namespace
}  // namespace ident::approx
