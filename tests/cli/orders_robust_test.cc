// `ident orders --estimator cauchy|student`: the reported Student-t NLL, scale and criteria against an
// independent computation (the residuals of the reported θ formed here, the NLL minimised over γ by a
// golden-section search), the structure BIC picks on an ARX(2,2,1) record with gross outliers, and the
// refusal of FPE.
#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "ident/workflow/student_likelihood.h"
#include "tests/support/cli.h"

namespace ident::testing {
namespace {

struct Record {
  std::vector<double> y, u;
  std::string path;
};

// y(t) = 1.5 y(t−1) − 0.7 y(t−2) + u(t−1) + 0.5 u(t−2) + e(t), e ~ N(0, σ²) with σ = 0.1, u ~ N(0, 1); then a
// fraction `outliers` of the measured outputs moved by ±50σ. Normal draws by Box–Muller on mt19937 so that the
// record is the same with every standard library. Written with 17 digits: the CSV holds these values exactly.
Record SimulateArx221(int rows, double outliers, std::uint32_t seed, const std::string& name) {
  std::mt19937 rng(seed);
  auto uniform = [&rng] { return (static_cast<double>(rng()) + 0.5) / 4294967296.0; };
  auto normal = [&] { return std::sqrt(-2 * std::log(uniform())) * std::cos(2 * std::numbers::pi * uniform()); };
  constexpr double sigma = 0.1;
  Record r;
  r.y.assign(rows, 0.0);
  r.u.resize(rows);
  for (int t = 0; t < rows; ++t) r.u[t] = normal();
  for (int t = 0; t < rows; ++t) {
    double y = sigma * normal();
    if (t >= 1) y += 1.5 * r.y[t - 1] + r.u[t - 1];
    if (t >= 2) y += -0.7 * r.y[t - 2] + 0.5 * r.u[t - 2];
    r.y[t] = y;
  }
  for (int t = 0; t < rows; ++t)
    if (uniform() < outliers) r.y[t] += (uniform() < 0.5 ? -50 : 50) * sigma;
  std::string text = "y,u\n";
  for (int t = 0; t < rows; ++t) text += fmt::format("{:.17g},{:.17g}\n", r.y[t], r.u[t]);
  r.path = WriteFile(name, text);
  return r;
}

// The one-step residuals y(t) − θ'[−y(t−1) … −y(t−na), u(t−nk) … u(t−nk−nb+1)] for t in [first, last).
std::vector<double> Residuals(const Record& r, const nlohmann::json& s, int first, int last) {
  const int na = s["na"], nb = s["nb"], nk = s["nk"];
  const std::vector<double> theta = s["theta"];
  std::vector<double> e;
  for (int t = first; t < last; ++t) {
    double prediction = 0;
    for (int i = 1; i <= na; ++i) prediction -= theta[i - 1] * r.y[t - i];
    for (int j = 0; j < nb; ++j) prediction += theta[na + j] * r.u[t - nk - j];
    e.push_back(r.y[t] - prediction);
  }
  return e;
}

// −Σ log p(e_i | γ) of the Student-t_k density Γ((k+1)/2)/(Γ(k/2)√(kπ) γ) · (1 + e²/(kγ²))^(−(k+1)/2), summed
// term by term from the density's definition.
double NegLogLikelihood(const std::vector<double>& e, double k, double gamma) {
  double sum = 0;
  for (const double x : e) {
    const double log_density = std::lgamma((k + 1) / 2) - std::lgamma(k / 2) - 0.5 * std::log(k * std::numbers::pi) -
                               std::log(gamma) - (k + 1) / 2 * std::log(1 + x * x / (k * gamma * gamma));
    sum -= log_density;
  }
  return sum;
}

// min over γ of NLL by golden-section search on log γ over [log(rms) − 12, log(rms) + 3], to a bracket of 1e-13.
std::pair<double, double> MinimiseOverScale(const std::vector<double>& e, double k) {
  double ms = 0;
  for (const double x : e) ms += x * x / static_cast<double>(e.size());
  double a = 0.5 * std::log(ms) - 12, b = 0.5 * std::log(ms) + 3;
  const double g = (std::sqrt(5.0) - 1) / 2;
  double c = b - g * (b - a), d = a + g * (b - a);
  double fc = NegLogLikelihood(e, k, std::exp(c)), fd = NegLogLikelihood(e, k, std::exp(d));
  while (b - a > 1e-13) {
    if (fc < fd) {
      b = d, d = c, fd = fc;
      c = b - g * (b - a);
      fc = NegLogLikelihood(e, k, std::exp(c));
    } else {
      a = c, c = d, fc = fd;
      d = a + g * (b - a);
      fd = NegLogLikelihood(e, k, std::exp(d));
    }
  }
  const double gamma = std::exp(0.5 * (a + b));
  return {NegLogLikelihood(e, k, gamma), gamma};
}

TEST(StudentLikelihood, TwoCauchyResidualsHaveTheirSizeAsScale) {
  // k = 1, residuals ±a: Σ 2a²/(γ² + a²) = 2 gives γ = a, NLL = 2 (log 2 + log a + log π).
  const auto p = workflow::ProfileStudentLikelihood({-0.3, 0.3}, 1.0);
  EXPECT_NEAR(p.scale, 0.3, 1e-15);
  EXPECT_NEAR(p.nll, 2 * (std::log(2.0) + std::log(0.3) + std::log(std::numbers::pi)), 1e-14);
}

TEST(OrdersRobust, NllScaleAndCriteriaEqualAnIndependentComputation) {
  constexpr int kRows = 300;
  const Record r = SimulateArx221(kRows, 0.05, 7, "robust_scores.csv");
  const int estimation_rows = kRows / 2, t0 = 2;  // --split 0.5; t0 = max(na_max, nk_max + nb_max − 1)
  for (const auto& [estimator, k] :
       std::vector<std::pair<std::string, double>>{{"cauchy", 1.0}, {"student --dof 3", 3.0}, {"student:7.5", 7.5}}) {
    const CliResult out = RunCli("orders " + r.path +
                                 " --output y --input u --na 1:2 --nb 1:2 --nk 1 --detrend none "
                                 "--criterion aic --json --estimator " +
                                 estimator);
    ASSERT_EQ(out.exit_code, 0) << out.err;
    const nlohmann::json j = nlohmann::json::parse(out.out);
    EXPECT_EQ(j["estimator"], k == 1 ? "cauchy" : fmt::format("student:{:g}", k));
    ASSERT_EQ(j["structures"].size(), 4u);
    EXPECT_EQ(j["samples"], estimation_rows - t0);
    EXPECT_EQ(j["validation_samples"], kRows - estimation_rows - t0);
    for (const auto& s : j["structures"]) {
      const std::string name =
          fmt::format("{} ARX({},{},{})", estimator, s["na"].get<int>(), s["nb"].get<int>(), s["nk"].get<int>());
      const std::vector<double> e = Residuals(r, s, t0, estimation_rows);
      const std::vector<double> v = Residuals(r, s, estimation_rows + t0, kRows);
      const auto [nll, gamma] = MinimiseOverScale(e, k);
      const double n = static_cast<double>(e.size()), p = s["n_parameters"].get<double>() + 1;  // θ and γ
      double ms = 0;
      for (const double x : e) ms += x * x / n;
      EXPECT_NEAR(s["loss"].get<double>(), ms, 1e-12 * ms) << name;
      EXPECT_NEAR(s["nll"].get<double>(), nll, 1e-8 * std::abs(nll)) << name;
      EXPECT_NEAR(s["scale"].get<double>(), gamma, 1e-6 * gamma) << name;
      EXPECT_NEAR(s["aic"].get<double>(), 2 * nll + 2 * p, 1e-8 * std::abs(nll)) << name;
      EXPECT_NEAR(s["bic"].get<double>(), 2 * nll + p * std::log(n), 1e-8 * std::abs(nll)) << name;
      EXPECT_NEAR(s["mdl"].get<double>(), nll + p / 2 * std::log(n), 1e-8 * std::abs(nll)) << name;
      EXPECT_TRUE(s["fpe"].is_null()) << name;
      const double validation = NegLogLikelihood(v, k, s["scale"].get<double>());
      EXPECT_NEAR(s["validation_nll"].get<double>(), validation, 1e-10 * std::abs(validation)) << name;
    }
    for (std::size_t i = 1; i < j["structures"].size(); ++i)
      EXPECT_LE(j["structures"][i - 1]["aic"].get<double>(), j["structures"][i]["aic"].get<double>());
  }
}

TEST(OrdersRobust, CauchyBicPicksTheTrueStructureDespiteGrossOutliers) {
  const Record r = SimulateArx221(400, 0.05, 2024, "robust_outliers.csv");
  const std::string grid = " --output y --input u --na 1:3 --nb 1:3 --nk 0:2 --split 1 --criterion bic --json";
  const CliResult robust = RunCli("orders " + r.path + grid + " --estimator cauchy");
  ASSERT_EQ(robust.exit_code, 0) << robust.err;
  const nlohmann::json best = nlohmann::json::parse(robust.out)["best"];
  EXPECT_EQ(best["na"], 2);
  EXPECT_EQ(best["nb"], 2);
  EXPECT_EQ(best["nk"], 1);
  // Least squares on the same record, reported only: its BIC follows the outliers to larger orders.
  const CliResult ls = RunCli("orders " + r.path + grid);
  ASSERT_EQ(ls.exit_code, 0) << ls.err;
  const nlohmann::json ls_best = nlohmann::json::parse(ls.out)["best"];
  std::printf("least-squares BIC picks ARX(%d,%d,%d); cauchy BIC ARX(%d,%d,%d)\n", ls_best["na"].get<int>(),
              ls_best["nb"].get<int>(), ls_best["nk"].get<int>(), best["na"].get<int>(), best["nb"].get<int>(),
              best["nk"].get<int>());
}

TEST(OrdersRobust, FpeWithARobustEstimatorIsRefused) {
  ExpectCliError("orders dryer --output y --input u --na 1:2 --nb 1:2 --nk 1 --estimator cauchy --criterion fpe",
                 "--criterion fpe is not likelihood-based");
  ExpectCliError("orders dryer --output y --input u --na 1:2 --nb 1 --nk 1 --estimator huber",
                 "need rls, cauchy or student:K");
  ExpectCliError("orders dryer --output y --input u --na 1:2 --nb 1 --nk 1 --estimator student", "needs dof k > 0");
}

}  // namespace
}  // namespace ident::testing
