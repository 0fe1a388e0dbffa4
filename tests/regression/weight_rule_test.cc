// A weight rule of one's own, defined in this file alone and run through the registry: the LD-form shell
// (ident/regression/weighted_regression.h) is the extension point, RegisterRegressionEstimator the way in.
// The rule here: a sample whose prediction error is within k residual scales weighs as in least squares,
// one beyond it k²/u of that (u = ê²/σ̂²), so its pull k²σ̂²/|ê| fades with its size (a redescending ψ with
// a logarithmic ρ tail) and its share of the residual scale stays below k²σ̂² — a Huber weight k/√u would
// let every gross error inflate the scale the rule itself reads (Huber's ψ² is unbounded in that sense).
// Checked against the truth of a simulated static regression with gross errors of one sign, against least
// squares on the same data, and for the shell's real-time promise (no allocation after construction).
#include <algorithm>
#include <cmath>
#include <memory>
#include <random>
#include <string>
#include <type_traits>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Core>

#include "common/error.h"
#include "ident/registry/estimator_registry.h"
#include "ident/regression/rls.h"
#include "ident/regression/weighted_regression.h"
#include "tests/support/alloc_counter.h"

namespace ident {
namespace {

// ν·β = min(1, k²/u), u = ξ_z − ξ the squared prediction error in residual scales [spec §3]; the first
// `warm_up` samples weigh fully, while the residual scale is still the prior's.
struct FadingWeight {
  static constexpr bool kNeedsXi = true;
  double k = 2.0;
  double warm_up = 30;
  double operator()(double nu, const Innovation& in) const noexcept {
    const double u = in.xi_z - in.xi;
    const double w = nu <= warm_up || !(u > k * k) ? 1.0 : k * k / u;
    return w / nu;
  }
};

const std::string& RegisteredFadingWeight() {
  static const std::string name = [] {
    RegisterRegressionEstimator(
        "fading-weight",
        [](const EstimatorSettings& s, int rho) {
          IDENT_REQUIRE(!s.dof && !s.exact && !s.lock_in.any(), "fading-weight takes forgetting and a prior only");
          return std::make_unique<RegressionEstimatorModel<BasicWeightedRegression<FadingWeight>>>(
              "fading-weight", rho, RlsOptions{s.forgetting, s.prior});
        },
        {.data_scaled_prior = true});
    return std::string("fading-weight");
  }();
  return name;
}

// y = 1 + 2 x1 − x2 + e, e ~ N(0, 0.1²), x ~ N(0, I); 5 % of the rows get +50·0.1 added to y (gross errors
// of one sign, which bias least squares' intercept by about 0.05·5 = 0.25).
struct OutlierRecord {
  Eigen::MatrixXd Z;
  Eigen::VectorXd y;
};
OutlierRecord SimulatedWithOutliers(int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> N(0, 1);
  std::uniform_real_distribution<double> U(0, 1);
  OutlierRecord r{Eigen::MatrixXd(n, 3), Eigen::VectorXd(n)};
  for (int i = 0; i < n; ++i) {
    r.Z.row(i) << 1, N(rng), N(rng);
    r.y(i) = r.Z.row(i).dot(Eigen::Vector3d(1, 2, -1)) + 0.1 * N(rng);
    if (U(rng) < 0.05) r.y(i) += 5.0;
  }
  return r;
}

EstimatorSettings Named(const std::string& name) {
  EstimatorSettings s;
  s.name = name;
  return s;
}

Eigen::VectorXd RunRecord(AnyRegressionEstimator& e, const OutlierRecord& r) {
  for (int i = 0; i < r.y.size(); ++i) e.Update(r.y(i), r.Z.row(i).transpose());
  return e.parameters();
}

TEST(WeightRule, ARuleOfOnesOwnIsInTheRegistryByName) {
  const std::string& name = RegisteredFadingWeight();
  const std::vector<std::string> names = RegressionEstimatorNames();
  EXPECT_NE(std::find(names.begin(), names.end(), name), names.end());
  EXPECT_TRUE(RegressionEstimatorTraits(name).data_scaled_prior);
  EXPECT_EQ(MakeRegressionEstimator(Named(name), 3)->name(), name);
  auto factory = [](const EstimatorSettings&, int rho) { return MakeRegressionEstimator(Named("rls"), rho); };
  EXPECT_THROW(RegisterRegressionEstimator(name, factory), InvalidArgument);     // taken
  EXPECT_THROW(RegisterRegressionEstimator("rls", factory), InvalidArgument);    // built in
  EXPECT_THROW(RegisterRegressionEstimator("a:b", factory), InvalidArgument);    // not a name
  EXPECT_THROW(RegisterRegressionEstimator("fresh", nullptr), InvalidArgument);  // no factory
  EstimatorSettings with_dof = Named(name);
  with_dof.dof = 3.0;
  EXPECT_THROW(MakeRegressionEstimator(with_dof, 3), InvalidArgument);
  // A key of its own that no regression estimator takes: refused by name (a registered estimator takes none).
  EstimatorSettings with_key = Named(name);
  with_key.options["points"] = "9";
  try {
    MakeRegressionEstimator(with_key, 3);
    ADD_FAILURE() << "the key was taken";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("has no option 'points' (it takes no options)"), std::string::npos)
        << e.what();
  }
}

// Over 20 seeds: the fading weight stays within a few hundredths of the truth where least squares is off
// by about 0.25 (the one pass weighs each sample against the estimate of its time, and the first samples
// fully, so it is not exact).
TEST(WeightRule, AFadingWeightKeepsTheModelThatLeastSquaresLosesToGrossErrors) {
  const std::string& name = RegisteredFadingWeight();
  const Eigen::Vector3d truth(1, 2, -1);
  std::vector<double> error, error_ls;
  for (unsigned seed = 1; seed <= 20; ++seed) {
    const OutlierRecord r = SimulatedWithOutliers(2000, seed);
    auto fading = MakeRegressionEstimator(Named(name), 3);
    auto rls = MakeRegressionEstimator(Named("rls"), 3);
    const Eigen::VectorXd theta = RunRecord(*fading, r), theta_ls = RunRecord(*rls, r);
    error.push_back((theta - truth).cwiseAbs().maxCoeff());
    error_ls.push_back((theta_ls - truth).cwiseAbs().maxCoeff());
    EXPECT_LT(error.back(), 0.25 * error_ls.back()) << "seed " << seed;
  }
  auto median = [](std::vector<double> v) {
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    return v[v.size() / 2];
  };
  EXPECT_GT(median(error_ls), 0.2);
  EXPECT_LT(median(error), 0.02);
  EXPECT_LT(*std::max_element(error.begin(), error.end()), 0.05);
}

TEST(WeightRule, TheShellWithARuleOfOnesOwnAllocatesNothingAfterConstruction) {
  BasicWeightedRegression<FadingWeight, 3> fixed(3);
  BasicWeightedRegression<FadingWeight> dynamic(3);
  const OutlierRecord r = SimulatedWithOutliers(2000, 7);
  testing::AllocationCounter count;
  for (int i = 0; i < r.y.size(); ++i) {
    const Eigen::Vector3d z = r.Z.row(i).transpose();
    fixed.Update(r.y(i), z);
    dynamic.Update(r.y(i), z);
  }
  EXPECT_EQ(count.allocations(), 0);
  EXPECT_EQ(fixed.parameters(), dynamic.parameters());
  EXPECT_LT((fixed.parameters() - Eigen::Vector3d(1, 2, -1)).cwiseAbs().maxCoeff(), 0.015);
}

// The least-squares rule is recursive least squares itself: the same type, the same bits.
TEST(WeightRule, LeastSquaresWeightIsRecursiveLeastSquares) {
  static_assert(std::is_same_v<BasicWeightedRegression<LeastSquaresWeight>, RecursiveLeastSquares>);
  const OutlierRecord r = SimulatedWithOutliers(500, 9);
  RecursiveLeastSquares rls(3);
  EstimatorSettings flat = Named("rls");
  flat.prior = RegressionPrior::Flat(3);
  auto by_name = MakeRegressionEstimator(flat, 3);
  for (int i = 0; i < r.y.size(); ++i) rls.Update(r.y(i), r.Z.row(i).transpose());
  EXPECT_EQ(Eigen::VectorXd(rls.parameters()), RunRecord(*by_name, r));
}

}  // namespace
}  // namespace ident
