// The data-driven start-up prior of StudentRegression (spec §8's D_y(0) hazard).
#include <cmath>
#include <random>

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "ident/regression/student_regression.h"
#include "tests/support/cli.h"

namespace ident {
namespace {

TEST(StartupPrior, IsScaleInvariantAfterTheWindow) {
  // y → c·y, z → T·z (diagonal): the robust scales scale along, so β(t) after the window is identical.
  std::mt19937_64 rng(6);
  std::normal_distribution<double> g;
  std::cauchy_distribution<double> e(0, 0.05);
  StudentRegression a(2), b(2);
  ASSERT_TRUE(a.in_startup());
  const double c = 1e3;
  const Eigen::Vector2d T(1e-2, 7.0);
  for (int t = 0; t < 300; ++t) {
    const Eigen::Vector2d z(g(rng), g(rng));
    const double y = 0.8 * z(0) - 0.3 * z(1) + e(rng);
    const double ba = a.Update(y, z).weight, bb = b.Update(c * y, Eigen::Vector2d(T.cwiseProduct(z))).weight;
    if (t >= 20) {
      EXPECT_NEAR(bb / ba, 1, 1e-10) << t;
    }
  }
  EXPECT_FALSE(a.in_startup());
  EXPECT_NEAR(b.parameters()(0), c * a.parameters()(0) / T(0), 1e-9 * std::abs(c * a.parameters()(0) / T(0)));
  EXPECT_NEAR(std::sqrt(b.Dy()), c * std::sqrt(a.Dy()), 1e-9 * c * std::sqrt(a.Dy()));
}

TEST(StartupPrior, PriorFollowsTheRuleAndExactSwitchesItOff) {
  StudentRegressionOptions o;
  o.startup_window = 5;
  StudentRegression est(1, o);
  const double ys[] = {1, 2, 3, 4, 100}, zs[] = {2, 2, 2, 2, 2};  // median 3, MAD 1; z constant → RMS 2
  for (int t = 0; t < 5; ++t) est.Update(ys[t], Eigen::VectorXd::Constant(1, zs[t]));
  EXPECT_DOUBLE_EQ(est.prior().nu0, 1 + 1 + 1);
  EXPECT_DOUBLE_EQ(est.prior().V0(0, 0), 1.4826 * 1.4826);
  EXPECT_DOUBLE_EQ(est.prior().V0(1, 1), 4.0 / (100 * 1));
  EXPECT_EQ(est.prior().V0(0, 1), 0);
  o.exact = true;
  StudentRegression exact(1, o);
  EXPECT_FALSE(exact.in_startup());
  EXPECT_DOUBLE_EQ(exact.prior().V0(0, 0), 1);
  o.exact = false;
  o.startup_window = 1;
  EXPECT_THROW(StudentRegression(1, o), InvalidArgument);
}

// On the bundled records the default (SafeStudentRegression: robust start-up prior, lock-in monitor) is
// compared with a range of fixed prior scales D_y(0) ∈ {1e−6, 1e−2, 1, 100} (ν0 = 6, V_z(0) = 1e−3·I,
// plain recursion otherwise), whose validation fits spread by up to 21 points (gas_furnace with
// cleaning), with the regressor cleaning on (the default) and off. The default must be within
// 2.5 points of the best fixed scale and not below the worst by more than 0.5.
TEST(StartupPrior, DefaultIsCloseToTheBestFixedPriorScaleOnRealRecords) {
  for (const std::string data :
       {"dryer --output y --input u --na 2 --nb 2 --nk 3", "gas_furnace --output y --input u --na 2 --nb 2 --nk 3",
        "exchanger --output y --input u --na 2 --nb 2 --nk 1"})
    for (const std::string clean : {"on", "off"}) {
      // A fixed scale far below the noise can leave the plain recursion with every sample weighted as an
      // outlier: its standard errors are not defined and ident refuses the result; such a scale is left out.
      auto fit = [&](const std::string& prior, bool may_be_unusable) {
        const testing::CliResult r =
            testing::RunCli("fit " + data + " --estimator cauchy --clean-regressors " + clean + " --json " + prior);
        if (may_be_unusable && r.exit_code == 1 && r.err.find("the result is unusable") != std::string::npos)
          return std::nan("");
        EXPECT_EQ(r.exit_code, 0) << r.err;
        return r.exit_code == 0 ? nlohmann::json::parse(r.out)["fit_percent"]["one_step"].get<double>() : std::nan("");
      };
      double best = -1e9, worst = 1e9;
      int usable = 0;
      for (const char* vy0 : {"1e-6", "1e-2", "1", "100"}) {
        const double f = fit(fmt::format("--nu0 6 --vy0 {} --vz0 1e-3 --exact", vy0), true);
        if (std::isnan(f)) continue;
        ++usable;
        best = std::max(best, f);
        worst = std::min(worst, f);
      }
      EXPECT_GE(usable, 3) << data << " cleaning " << clean;
      const double ours = fit("", false);
      EXPECT_GT(ours, best - 2.5) << data << " cleaning " << clean;
      EXPECT_GT(ours, worst - 0.5) << data << " cleaning " << clean;
    }
}

}  // namespace
}  // namespace ident
