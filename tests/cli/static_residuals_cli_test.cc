// The residual whiteness and input-correlation tests ask about lags in time: `ident fit` reports them for
// dynamic structures only, not for a static regression (--regressors), whose JSON keeps the keys.
#include <string>

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "tests/support/cli.h"

namespace ident::testing {
namespace {

std::string StaticRecord() {
  std::string text = "x,y\n";
  for (int i = 0; i < 200; ++i) {
    const double x = (i * 37 % 101) / 10.0;
    text += fmt::format("{},{}\n", x, 2 * x + ((i * 53) % 7 - 3) / 10.0);
  }
  return text;
}

TEST(StaticResiduals, NoWhitenessOrInputCorrelationForAStaticRegression) {
  const std::string path = WriteFile("static_record.csv", StaticRecord());
  const std::string args = "fit " + path + " --output y --regressors x --intercept";
  const CliResult json = RunCli(args + " --json");
  ASSERT_EQ(json.exit_code, 0) << json.err;
  const nlohmann::json a = nlohmann::json::parse(json.out)["residual_analysis"];
  ASSERT_TRUE(a.is_object());
  EXPECT_EQ(a["applies"], false);
  EXPECT_EQ(a["samples"], 100);
  for (const char* key : {"autocorrelation", "cross_correlation", "q_auto", "q_auto_limit", "white", "independent"}) {
    ASSERT_TRUE(a.contains(key)) << key;
    EXPECT_TRUE(a[key].is_null()) << key;
  }
  const CliResult text = RunCli(args);
  ASSERT_EQ(text.exit_code, 0) << text.err;
  EXPECT_EQ(text.out.find("whiteness"), std::string::npos) << text.out;
  EXPECT_EQ(text.out.find("r_eu"), std::string::npos) << text.out;
  EXPECT_NE(text.out.find("static regression"), std::string::npos) << text.out;
}

TEST(StaticResiduals, ArxKeepsBothTests) {
  const CliResult r = RunCli("fit dryer --output y --input u --na 2 --nb 2 --nk 3 --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json a = nlohmann::json::parse(r.out)["residual_analysis"];
  EXPECT_EQ(a["applies"], true);
  EXPECT_EQ(a["autocorrelation"].size(), 20u);
  EXPECT_EQ(a["cross_correlation"]["u"].size(), 21u);
  EXPECT_TRUE(a["white"].is_boolean());
}

// Progress goes to stderr only once a command has run 2 s: short runs print nothing there. (A multi-pass fit
// without lock-in restarts: the end-of-data competition of a robust fit takes about a second in the
// sanitizer build at -O0, too close to 2 s to count as short.)
TEST(Progress, ShortRunsPrintNothingOnStderr) {
  for (const std::string args : {"fit dryer --output y --input u --na 2 --nb 2 --nk 3 --passes 2 --estimator cauchy "
                                 "--no-lock-in-restart",
                                 "orders dryer --output y --input u --na 1:3 --nb 1:3 --nk 1:3"}) {
    const CliResult r = RunCli(args);
    EXPECT_EQ(r.exit_code, 0) << args << "\n" << r.err;
    EXPECT_EQ(r.err, "") << args;
  }
}

}  // namespace
}  // namespace ident::testing
