// Where `ident fit` stops reading a record whole and streams it: at more than 10^6 data rows, the lines that
// are neither blank nor comments, less the header (the first line of a file without one is a data row of the
// table but not of the count). The records here look short to the guess that spares a row count (their first
// and last 64 KiB hold a few long comment lines), so a longer one is found long by the whole read itself, which
// stops after 10^6 + 2 rows.
#include <cmath>
#include <random>
#include <string>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "tests/support/cli.h"

namespace ident {
namespace {

using testing::RunCli;

constexpr long kInMemoryRows = 1'000'000;
constexpr const char* kStreamed = "residual analysis: skipped (record of more than 1000000 rows, streamed)";

// `lines` lines of u, y from y(t) = 0.5 y(t−1) + u(t−1) + 0.1 e(t), u = ±1 (a header "u,y" first if `header`,
// counted in `lines`), y to 3 significant digits so that the rows are short, between ten comment lines of 8 000
// bytes at the start and at the end.
std::string PaddedRecord(long lines, bool header) {
  const std::string comment = "# " + std::string(8'000, '-') + "\n";
  std::string text;
  for (int i = 0; i < 10; ++i) text += comment;
  if (header) text += "u,y\n";
  std::mt19937_64 rng(5);
  std::normal_distribution<double> normal;
  double y1 = 0, u1 = 0;
  for (long k = header ? 1 : 0; k < lines; ++k) {
    const double u = normal(rng) > 0 ? 1.0 : -1.0;
    const double y = 0.5 * y1 + u1 + 0.1 * normal(rng);
    text += fmt::format("{:g},{:.3g}\n", u, y);
    y1 = y, u1 = u;
  }
  for (int i = 0; i < 10; ++i) text += comment;
  return text;
}

// The printed estimate of `name` in a text report ("  a1   -0.5 ...").
double Estimate(const std::string& out, const std::string& name) {
  const std::size_t at = out.find("\n  " + name + " ");
  return at == std::string::npos ? NAN : std::stod(out.substr(at + 3 + name.size()));
}

TEST(InMemoryThreshold, TenToTheSixDataRowsAreReadWholeOneMoreIsStreamed) {
  struct Case {
    long lines;
    bool header;
    bool streamed;
  };
  for (const Case c : {Case{kInMemoryRows + 1, true, false}, Case{kInMemoryRows + 2, true, true},
                       Case{kInMemoryRows + 1, false, false}, Case{kInMemoryRows + 2, false, true}}) {
    const std::string label = fmt::format("{} lines, {}", c.lines, c.header ? "a header" : "no header");
    SCOPED_TRACE(label);
    const std::string path = testing::WriteFile("threshold.csv", PaddedRecord(c.lines, c.header));
    const std::string columns = c.header ? " --output y --input u" : " --output c2 --input c1";
    const testing::CliResult r = RunCli("fit " + path + columns + " --na 1 --nb 1 --nk 1 --estimator rls");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_EQ(r.out.find(kStreamed) != std::string::npos, c.streamed) << r.out;
    EXPECT_EQ(r.out.find("residual analysis (validation") != std::string::npos, !c.streamed) << r.out;
    // A real fit either way: the system's parameters (y's rounding adds noise of about 1e-3).
    EXPECT_NEAR(Estimate(r.out, "a1"), -0.5, 0.01) << r.out;
    EXPECT_NEAR(Estimate(r.out, "b1"), 1.0, 0.01) << r.out;
  }
}

}  // namespace
}  // namespace ident
