// ident mems end to end: table, CSV columns, traces, bad options.
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "tests/support/cli.h"
#include "tests/support/sanitizer.h"

namespace ident {
namespace {

TEST(MemsCli, WritesOneCsvRowPerRateWithTheRequiredColumns) {
  const std::string dir = testing::TempDir();
  const int steps = testing::FullOrUnderSanitizer(400, 150);  // tests/support/sanitizer.h
  // Under the sanitizers the grid is not refined (the refinement check has tests of its own).
  const std::string grid = testing::FullOrUnderSanitizer<std::string>("", " --grid-tolerance 0");
  const auto r = testing::RunCli("mems --steps " + std::to_string(steps) + " --grid-points 32" + grid +
                                 " --t-mean 0.5,1 --csv " + dir + "/fig9.csv --trace " + dir + "/fig8.csv");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("RMS velocity error"), std::string::npos);
  std::istringstream csv(testing::ReadFile(dir + "/fig9.csv"));
  std::string header, line;
  std::getline(csv, header);
  for (const char* col : {"t_mean", "rms_grid", "rms_tuned_kalman", "rms_lc_gaussian", "rms_bound",
                          "calibration_lc_gaussian", "calibration_se_lc_gaussian", "calibration_se_grid"})
    EXPECT_NE(header.find(col), std::string::npos) << col;
  EXPECT_NE(r.out.find("jackknife standard error"), std::string::npos) << r.out;
  int rows = 0;
  while (std::getline(csv, line))
    if (!line.empty()) ++rows;
  EXPECT_EQ(rows, 2);
  std::istringstream trace(testing::ReadFile(dir + "/fig8.csv"));
  std::getline(trace, header);
  EXPECT_EQ(header, "t,x1,y,var_grid,var_tuned_kalman,var_lc_gaussian,var_bound");
  rows = 0;
  while (std::getline(trace, line))
    if (!line.empty()) ++rows;
  EXPECT_EQ(rows, steps);
}

TEST(MemsCli, BadOptionsExitWithOneLineNamingTheOption) {
  auto r = testing::RunCli("mems --steps 10");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("steps"), std::string::npos) << r.err;
  r = testing::RunCli("mems --t-mean -1");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("--t-mean"), std::string::npos) << r.err;
  r = testing::RunCli("mems --steps 400 --grid-points 32 --t-mean 1 --plot /tmp/x.unknown");
  EXPECT_EQ(r.exit_code, 1);
  r = testing::RunCli("mems --no-such-option");
  EXPECT_EQ(r.exit_code, 2);
}

}  // namespace
}  // namespace ident
