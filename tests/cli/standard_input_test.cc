// Records from standard input ("-"), a pipe (/dev/stdin) and a FIFO: read once, with the numbers a
// regular file gives.
#include <sys/wait.h>

#include <cstdlib>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "tests/support/cli.h"
#include "tests/support/test_data.h"

namespace ident::testing {
namespace {

// Runs a shell command line (with its own redirections and pipes) whose `ident` is the program under test.
CliResult Shell(const std::string& line) {
  static int counter = 0;
  const std::string base = TempDir() + "/shell" + std::to_string(counter++);
  std::string command = line;
  for (std::size_t at = command.find("IDENT"); at != std::string::npos; at = command.find("IDENT", at))
    command.replace(at, 5, std::string("'") + IDENT_CLI_PATH + "'");
  const int status = std::system(("(" + command + ") > '" + base + ".out' 2> '" + base + ".err'").c_str());
  CliResult r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  r.out = ReadFile(base + ".out");
  r.err = ReadFile(base + ".err");
  return r;
}

nlohmann::json WithoutData(const CliResult& r) {
  EXPECT_EQ(r.exit_code, 0) << r.err;
  nlohmann::json j = nlohmann::json::parse(r.out);
  j.erase("data");
  return j;
}

TEST(StandardInput, FitFromStdinAPipeAndAFifoGivesTheFilesNumbers) {
  const std::string file = DatasetPath("dryer.csv");
  const std::string args = " --output y --input u --na 2 --nb 2 --nk 3 --estimator cauchy --json";
  const nlohmann::json expected = WithoutData(RunCli("fit " + file + args));
  EXPECT_EQ(WithoutData(Shell("IDENT fit -" + args + " < " + file)), expected);
  EXPECT_EQ(WithoutData(Shell("IDENT fit /dev/stdin" + args + " < " + file)), expected);
  EXPECT_EQ(WithoutData(Shell("cat " + file + " | IDENT fit /dev/stdin" + args)), expected);
  const std::string fifo = TempDir() + "/record.fifo";
  EXPECT_EQ(WithoutData(Shell("rm -f " + fifo + "; mkfifo " + fifo + " && (cat " + file + " > " + fifo +
                              " &) && IDENT fit " + fifo + args)),
            expected);
}

TEST(StandardInput, CompareOrdersAndPredictReadStdin) {
  const std::string file = DatasetPath("dryer.csv");
  const std::string arx = " --output y --input u --na 2 --nb 2 --nk 3";
  nlohmann::json a = WithoutData(RunCli("compare " + file + arx + " --estimators rls --json"));
  nlohmann::json b = WithoutData(Shell("IDENT compare -" + arx + " --estimators rls --json < " + file));
  a["estimators"][0].erase("ns_per_update");
  b["estimators"][0].erase("ns_per_update");
  EXPECT_EQ(a, b);
  EXPECT_EQ(WithoutData(RunCli("orders " + file + " --output y --input u --na 1:3 --json")),
            WithoutData(Shell("IDENT orders - --output y --input u --na 1:3 --json < " + file)));
  const std::string model = TempDir() + "/stdin_model.json";
  ASSERT_EQ(Shell("IDENT fit -" + arx + " --save " + model + " < " + file).exit_code, 0);
  const nlohmann::json m = nlohmann::json::parse(ReadFile(model));
  EXPECT_EQ(m["data"]["fnv1a64"], "");  // the bytes are gone: no checksum
  nlohmann::json p = WithoutData(Shell("IDENT predict " + model + " - --json < " + file));
  p.erase("model");
  nlohmann::json q = WithoutData(RunCli("predict " + model + " " + file + " --json"));
  q.erase("model");
  EXPECT_EQ(p, q);
}

TEST(StandardInput, BadInputFromStdinIsNamedAsSuch) {
  const CliResult r = Shell("IDENT fit - --output y --input u < /dev/null");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("standard input"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace ident::testing
