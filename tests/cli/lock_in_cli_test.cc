// The lock-in safeguard through the command line: `ident fit` reports the monitor's
// state under "lock_in" in --json (null for RLS and with --exact) and a line in the report, and
// --lock-in-window / --lock-in-threshold / --no-lock-in-restart reach the estimator. Checked on the seeded
// ARX record on which the Cauchy estimator locks in (tests/regression/lock_in_data.h): against the true Θ, and
// against SafeStudentRegression run directly on the same samples with the same options.
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "ident/regression/safe_student_regression.h"
#include "tests/regression/lock_in_data.h"
#include "tests/support/cli.h"

namespace ident {
namespace {

using testing::CliResult;
using testing::ExpectCliError;
using testing::RunCli;

// The lock-in record as a static regression y = Θ'z (z1..z4), fitted on every row from the prior
// ν(0) = 6, V(0) = diag(1e−6, 1e−3·I) whose tiny D_y(0) leads the plain recursion into the lock-in.
const char kPrior[] = " --nu0 6 --vy0 1e-6 --vz0 1e-3";
const char kModel[] = " --output y --regressors z1,z2,z3,z4 --detrend none --split 1";

struct Record {
  testing::LockInArx data;
  std::string path;
};

const Record& LockInRecord() {
  static const Record r = [] {
    Record rec{testing::SimulateLockInArx(/*seed=*/1001, /*n=*/2000), ""};
    std::string csv = "y,z1,z2,z3,z4\n";
    for (std::size_t t = 0; t < rec.data.y.size(); ++t) {
      const Eigen::Vector4d& z = rec.data.z[t];
      csv += fmt::format("{:.17g},{:.17g},{:.17g},{:.17g},{:.17g}\n", rec.data.y[t], z(0), z(1), z(2), z(3));
    }
    rec.path = testing::WriteFile("lock_in_arx.csv", csv);
    return rec;
  }();
  return r;
}

nlohmann::json FitJson(const std::string& args) {
  const CliResult r = RunCli("fit " + args + " --json");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  return r.exit_code == 0 ? nlohmann::json::parse(r.out) : nlohmann::json();
}

// The library estimator on the same samples, with the end-of-data steps `ident fit` takes.
SafeStudentRegression RunLibrary(SafeStudentOptions o) {
  o.base.prior = RegressionPrior::Diagonal(4, 6, 1e-6, 1e-3);
  SafeStudentRegression est(4, o);
  const testing::LockInArx& d = LockInRecord().data;
  for (std::size_t t = 0; t < d.y.size(); ++t) est.Update(d.y[t], d.z[t]);
  est.FinishStartup();
  est.ReconsiderAtEnd();
  return est;
}

double ThetaError(const nlohmann::json& j) {
  const std::vector<double> theta = j["theta"];
  return (Eigen::Vector4d(theta[0], theta[1], theta[2], theta[3]) - testing::kLockInTheta).norm();
}

void ExpectSameTheta(const nlohmann::json& j, const SafeStudentRegression& est) {
  const std::vector<double> theta = j["theta"];
  ASSERT_EQ(theta.size(), 4u);
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(theta[i], est.parameters()(i), 1e-12 * std::abs(est.parameters()(i))) << i;
}

TEST(LockInCli, DefaultRestartsOutOfTheLockInAndReportsIt) {
  const nlohmann::json j = FitJson(LockInRecord().path + kModel + kPrior + " --estimator cauchy");
  const SafeStudentRegression lib = RunLibrary({});
  ASSERT_TRUE(j["lock_in"].is_object()) << j.dump();
  EXPECT_EQ(j["lock_in"]["window"], 100);  // max(100, 20ρ), ρ = 4
  EXPECT_EQ(j["lock_in"]["threshold"], 0.3);
  EXPECT_EQ(j["lock_in"]["restart"], true);
  EXPECT_GE(j["lock_in"]["restarts"].get<int>(), 1);
  EXPECT_EQ(j["lock_in"]["restarts"], lib.restarts());
  EXPECT_EQ(j["lock_in"]["flagged"], lib.lock_ins());
  EXPECT_NEAR(j["lock_in"]["low_weight_fraction"].get<double>(), lib.monitor().low_fraction(), 1e-15);
  EXPECT_LT(j["lock_in"]["low_weight_fraction"].get<double>(), 0.5);  // not locked in at the end
  ExpectSameTheta(j, lib);
  EXPECT_LT(ThetaError(j), 0.05);  // σ = 0.1 on 2000 samples: the estimate is close to Θ
}

// --history-limit reaches the estimator: its restarts replay at most the last N samples and report the rest as
// dropped, as the library estimator's with the same history_limit do, and a limit below the lock-in window is
// refused by the estimator's own check.
TEST(LockInCli, HistoryLimitBoundsWhatARestartReplays) {
  const nlohmann::json j = FitJson(LockInRecord().path + kModel + kPrior + " --estimator cauchy --history-limit 300");
  SafeStudentOptions o;
  o.history_limit = 300;
  const SafeStudentRegression lib = RunLibrary(o);
  ASSERT_GE(lib.restarts(), 1);
  const nlohmann::json& events = j["lock_in"]["events"];
  ASSERT_EQ(events.size(), lib.restart_events().size()) << j.dump();
  for (std::size_t i = 0; i < events.size(); ++i) {
    const long update = events[i]["update"];
    EXPECT_EQ(events[i]["replayed"].get<long>(), std::min(update, 300L)) << i;
    EXPECT_EQ(events[i]["dropped"].get<long>(), update - std::min(update, 300L)) << i;
    EXPECT_EQ(events[i]["replayed"].get<long>(), lib.restart_events()[i].replayed) << i;
  }
  ExpectSameTheta(j, lib);
  const CliResult small =
      RunCli("fit " + LockInRecord().path + kModel + kPrior + " --estimator cauchy --history-limit 50");
  EXPECT_EQ(small.exit_code, 1);
  EXPECT_NE(small.err.find("history_limit = 50; need 0 (keep every sample) or at least the lock-in window 100"),
            std::string::npos)
      << small.err;
  EXPECT_EQ(RunCli("fit " + LockInRecord().path + kModel + " --history-limit 300").exit_code, 1);  // rls
}

TEST(LockInCli, NoRestartFlagsTheLockInAndStaysInIt) {
  const nlohmann::json j = FitJson(LockInRecord().path + kModel + kPrior + " --estimator cauchy --no-lock-in-restart");
  SafeStudentOptions o;
  o.restart_on_lock_in = false;
  const SafeStudentRegression lib = RunLibrary(o);
  EXPECT_EQ(j["lock_in"]["restart"], false);
  EXPECT_EQ(j["lock_in"]["restarts"], 0);
  EXPECT_GE(j["lock_in"]["flagged"].get<int>(), 100);  // flagged at every update while locked in
  EXPECT_EQ(j["lock_in"]["flagged"], lib.lock_ins());
  EXPECT_GT(j["lock_in"]["low_weight_fraction"].get<double>(), 0.5);  // most weights low: still locked in
  ExpectSameTheta(j, lib);
  EXPECT_GT(ThetaError(j), 0.3);  // the wrong mode of the lock-in
}

TEST(LockInCli, WindowAndThresholdReachTheEstimator) {
  const nlohmann::json j = FitJson(LockInRecord().path + kModel + kPrior +
                                   " --estimator cauchy --lock-in-window 60 --lock-in-threshold 0.2");
  SafeStudentOptions o;
  o.lock_in_window = 60;
  o.lock_in_threshold = 0.2;
  const SafeStudentRegression lib = RunLibrary(o), lib_default = RunLibrary({});
  EXPECT_EQ(j["lock_in"]["window"], 60);
  EXPECT_EQ(j["lock_in"]["threshold"], 0.2);
  EXPECT_GE(j["lock_in"]["restarts"].get<int>(), 1);
  EXPECT_EQ(j["lock_in"]["restarts"], lib.restarts());
  EXPECT_NEAR(j["lock_in"]["low_weight_fraction"].get<double>(), lib.monitor().low_fraction(), 1e-15);
  ExpectSameTheta(j, lib);
  // The options made a difference: another first restart than with the defaults.
  ASSERT_FALSE(lib.restart_events().empty());
  ASSERT_FALSE(lib_default.restart_events().empty());
  EXPECT_NE(lib.restart_events()[0].update, lib_default.restart_events()[0].update);
}

TEST(LockInCli, NullForRlsAndExactAndAReportLineForTheRobustOnes) {
  const std::string dryer = "dryer --output y --input u --na 2 --nb 2 --nk 3";
  EXPECT_TRUE(FitJson(dryer + " --estimator rls")["lock_in"].is_null());
  EXPECT_TRUE(FitJson(dryer + " --estimator cauchy --exact")["lock_in"].is_null());
  const CliResult r = RunCli("fit " + dryer + " --estimator cauchy");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // No lock-in; the end of the data finds a restart of higher likelihood.
  EXPECT_NE(r.out.find("lock-in monitor (window 100, weight threshold 0.3): flagged at 0 updates, 1 restart;"),
            std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("restart at the end of the data (update 496)"), std::string::npos) << r.out;
}

// silverbox (65 534 updates, heavier-tailed than Cauchy) in two passes: the lock-in monitor restarts in both, and
// the restarts of the second pass say which pass they belong to, in the JSON and in the report.
TEST(LockInCli, RestartsOfFurtherPassesNameTheirPass) {
  const nlohmann::json j = FitJson("silverbox_snls80mv --estimator cauchy --passes 2");
  const nlohmann::json& events = j["lock_in"]["events"];
  std::size_t second = events.size();
  for (std::size_t i = 0; i < events.size(); ++i) {
    const int pass = events[i]["pass"].get<int>();
    EXPECT_TRUE(pass == 1 || pass == 2) << i;
    if (i > 0) {
      EXPECT_GE(pass, events[i - 1]["pass"].get<int>()) << i;  // in the order they happened
    }
    if (pass == 2 && second == events.size()) second = i;
  }
  ASSERT_GT(second, 0u);             // the first pass restarts (heavy tails)
  ASSERT_LT(second, events.size());  // and so does the second
  const CliResult r = RunCli("fit silverbox_snls80mv --estimator cauchy --passes 2");
  EXPECT_NE(r.out.find(fmt::format("restart at update {} of pass 2:", events[second]["update"].get<long>())),
            std::string::npos)
      << r.out;
}

TEST(LockInCli, BadLockInOptionsExitOneAndSayWhy) {
  const std::string dryer = "fit dryer --output y --input u --na 2 --nb 2 --nk 3";
  ExpectCliError(dryer + " --estimator rls --lock-in-window 50", "lock-in options apply to the robust estimators");
  ExpectCliError(dryer + " --estimator cauchy --exact --no-lock-in-restart", "no effect with exact");
  ExpectCliError(dryer + " --estimator cauchy --lock-in-window 1",
                 "lock_in_window = 1; need 0 (automatic) or 2..1000000");
  ExpectCliError(dryer + " --estimator cauchy --lock-in-window -5", "lock_in_window = -5");
  ExpectCliError(dryer + " --estimator cauchy --lock-in-threshold 0", "lock-in threshold = 0");
  ExpectCliError(dryer + " --estimator cauchy --lock-in-threshold nan", "lock-in threshold = nan");
  // νβ of a sample fitted exactly is (k+1)/k: 2 for Cauchy, 4/3 for k = 3.
  ExpectCliError(dryer + " --estimator cauchy --lock-in-threshold 2", "need 0 < threshold < (k+1)/k = 2");
  ExpectCliError(dryer + " --estimator student --dof 3 --lock-in-threshold 1.5", "(k+1)/k = 1.333");
  EXPECT_EQ(RunCli(dryer + " --estimator cauchy --lock-in-window x").exit_code, 2);
}

}  // namespace
}  // namespace ident
