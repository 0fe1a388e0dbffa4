// Files as users bring them (ident/io/csv.h, ident/workflow/time_column.h): ';', tab and whitespace
// delimiters, '#' comments, headerless DaISy-style .dat files, --delimiter on every reading command, and
// the time column's gaps, which --missing fills with missing samples.
#include <cmath>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "tests/support/cli.h"
#include "tests/support/mat_writer.h"

namespace ident {
namespace {

using testing::CliResult;
using testing::ExpectCliError;
using testing::RunCli;
using testing::WriteFile;

// A record of y(k) = a y(k-1) + b u(k-1) without noise, k = 0..n-1, at times 0.1 k.
struct RealFileRecord {
  std::vector<double> t, u, y;
};
RealFileRecord RealFileNoiseless(int n, double a, double b) {
  RealFileRecord r;
  double y = 0;
  for (int k = 0; k < n; ++k) {
    const double u = std::sin(0.37 * k) + ((k * 7919) % 13 - 6) / 6.0;  // rich enough for two parameters
    r.t.push_back(0.1 * k);
    r.u.push_back(u);
    r.y.push_back(y);
    y = a * y + b * u;
  }
  return r;
}

// The record's rows except `dropped` (0-based), as text with `sep` between cells and '.' decimals.
std::string RealFileText(const RealFileRecord& r, const std::string& sep, bool header = true,
                         const std::vector<int>& dropped = {}) {
  std::string s = header ? fmt::format("t{0}u{0}y\n", sep) : "";
  for (std::size_t k = 0; k < r.t.size(); ++k) {
    if (std::find(dropped.begin(), dropped.end(), static_cast<int>(k)) != dropped.end()) continue;
    s += fmt::format("{0:.1f}{3}{1:.17g}{3}{2:.17g}\n", r.t[k], r.u[k], r.y[k], sep);
  }
  return s;
}

nlohmann::json RealFileFitJson(const std::string& args) {
  const CliResult r = RunCli("fit " + args + " --json");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  return r.exit_code == 0 ? nlohmann::json::parse(r.out) : nlohmann::json();
}

constexpr const char* kRealFileArx = " --output y --input u --na 1 --nb 1 --nk 1 --split 1 --detrend none";

// The same record as comma, ';', tab and whitespace text, with comments, gives the same fit bit for bit.
TEST(RealFiles, EveryDelimiterGivesTheSameFit) {
  const RealFileRecord r = RealFileNoiseless(200, 0.7, 0.5);
  const nlohmann::json comma = RealFileFitJson(WriteFile("rf_comma.csv", RealFileText(r, ",")) + kRealFileArx);
  ASSERT_TRUE(comma.contains("theta"));
  for (const auto& [name, text] : std::vector<std::pair<std::string, std::string>>{
           {"rf_semi.csv", "# exported with ';'\n" + RealFileText(r, ";")},
           {"rf_tab.tsv", RealFileText(r, "\t") + "# end\n"},
           {"rf_space.dat", "  # whitespace\n" + RealFileText(r, "   ")}}) {
    const nlohmann::json j = RealFileFitJson(WriteFile(name, text) + kRealFileArx);
    EXPECT_EQ(j["theta"], comma["theta"]) << name;
    EXPECT_EQ(j["samples_estimation"], 200) << name;
  }
  // --delimiter given, on fit and its --validate record.
  const std::string semi = WriteFile("rf_semi2.csv", RealFileText(r, ";"));
  const nlohmann::json given = RealFileFitJson(semi + kRealFileArx + " --delimiter ';' --validate " + semi);
  EXPECT_EQ(given["theta"], comma["theta"]);
}

// A headerless DaISy-style file: columns c1, c2, c3; the noiseless ARX is recovered.
TEST(RealFiles, HeaderlessDatFileHasColumnsC1ToCn) {
  const RealFileRecord r = RealFileNoiseless(200, 0.7, 0.5);
  const nlohmann::json j =
      RealFileFitJson(WriteFile("rf_daisy.dat", RealFileText(r, "  ", /*header=*/false)) +
                      " --output c3 --input c2 --na 1 --nb 1 --nk 1 --split 1 --detrend none --delimiter space");
  ASSERT_TRUE(j.contains("theta"));
  EXPECT_NEAR(j["theta"][0].get<double>(), -0.7, 1e-6);  // a1 of A(q) = 1 + a1 q^-1
  EXPECT_NEAR(j["theta"][1].get<double>(), 0.5, 1e-6);
}

TEST(RealFiles, DelimiterProblemsAreOneLineErrors) {
  const RealFileRecord r = RealFileNoiseless(20, 0.7, 0.5);
  const std::string semi = WriteFile("rf_wrong.csv", RealFileText(r, ";"));
  ExpectCliError("fit " + semi + kRealFileArx + " --delimiter ,",
                 "rf_wrong.csv:1: the header has one column with the delimiter ','; the file looks ';'-separated "
                 "(pass --delimiter ';')");
  ExpectCliError("fit " + WriteFile("rf_decimal.csv", "t;u;y\n0;1;2\n1;2,5;3\n") + kRealFileArx,
                 "rf_decimal.csv:3: column 2 ('u'): '2,5' is not a number (the delimiter is ';': decimals take '.'");
  ExpectCliError("fit " + WriteFile("rf_amb.csv", "t,u;y\n0,1;2\n") + kRealFileArx,
                 "rf_amb.csv:1: cannot tell the delimiter");
  ExpectCliError("orders " + semi + " --output y --input u --delimiter '|'", "--delimiter", 2);
}

// --delimiter reaches the reader of compare, orders, predict, stream, smooth and logcondens.
TEST(RealFiles, EveryReadingCommandTakesDelimiter) {
  const RealFileRecord r = RealFileNoiseless(300, 0.7, 0.5);
  const std::string semi = WriteFile("rf_cmds.csv", RealFileText(r, ";"));
  ExpectCliError("orders " + semi + " --output y --input u --delimiter tab",
                 "rf_cmds.csv:1: the header has one column with the delimiter tab");
  EXPECT_EQ(RunCli("orders " + semi + " --output y --input u --na 1:2 --nb 1:2 --nk 1 --delimiter ';'").exit_code, 0);
  ExpectCliError("compare " + semi + " --output y --input u --delimiter space",
                 "rf_cmds.csv:1: the header has one column with the delimiter space");
  ExpectCliError("logcondens " + semi + " --column u --delimiter ,", "rf_cmds.csv:1: the header has one column");
  const CliResult lc = RunCli("logcondens " + semi + " --column u --delimiter ';' --json");
  EXPECT_EQ(lc.exit_code, 0) << lc.err;
  const std::string model = testing::TempDir() + "/rf_model.json";
  ASSERT_EQ(RunCli("fit " + semi + kRealFileArx + " --save " + model).exit_code, 0);
  ExpectCliError("predict " + model + " " + semi + " --delimiter ,", "rf_cmds.csv:1: the header has one column");
  EXPECT_EQ(RunCli("predict " + model + " " + semi + " --delimiter ';' --json").exit_code, 0);
  ExpectCliError("stream " + semi + " --output y --input u --delimiter ,", "rf_cmds.csv:1: the header has one column");
  const CliResult st = RunCli("stream " + semi + " --output y --input u --na 1 --nb 1 --nk 1 --delimiter ';'");
  EXPECT_EQ(st.exit_code, 0) << st.err;
  EXPECT_EQ(std::count(st.out.begin(), st.out.end(), '\n'), 300);  // one JSON line per row
  const std::string smooth_model = WriteFile("rf_smooth.json", R"({"A": [[1]], "C": [[1]], "x0": [0],
    "process_penalty": {"type": "quadratic", "weight": 1}, "measurement_penalty": {"type": "quadratic", "weight": 1}})");
  ExpectCliError("smooth --model " + smooth_model + " " + WriteFile("rf_z.csv", "k;z\n0;1\n1;2\n") + " --delimiter ,",
                 "rf_z.csv:1: the header has one column");
}

// Gaps in the time column: reported; with --missing filled by missing rows, so no regression straddles a
// gap. On a noiseless record the regressions that do not straddle are exact equations: the filled fit
// recovers (a, b), rejecting m + 1 regressions per gap of m missing samples (m rows with y missing, and the
// row after them, whose regressor holds a missing y); the unfilled one regresses across the gaps and is off.
TEST(RealFiles, TimeGapsAreReportedAndFilledWithMissing) {
  const RealFileRecord r = RealFileNoiseless(400, 0.7, 0.5);
  std::vector<int> dropped;
  for (int k = 150; k < 160; ++k) dropped.push_back(k);  // m = 10
  for (int k = 300; k < 303; ++k) dropped.push_back(k);  // m = 3
  const std::string path = WriteFile("rf_gaps.csv", "# two gaps\n" + RealFileText(r, ",", true, dropped));
  const nlohmann::json filled = RealFileFitJson(path + kRealFileArx + " --missing");
  ASSERT_TRUE(filled.contains("time_gaps"));
  ASSERT_EQ(filled["time_gaps"].size(), 2u);
  EXPECT_EQ(filled["time_gaps"][0]["row"], 151);  // data row of t = 16.0
  EXPECT_EQ(filled["time_gaps"][0]["t_before"], 14.9);
  EXPECT_EQ(filled["time_gaps"][0]["t_after"], 16.0);
  EXPECT_EQ(filled["time_gaps"][0]["missing"], 10);
  EXPECT_EQ(filled["time_gaps"][0]["filled"], 10);
  EXPECT_EQ(filled["time_gaps"][1]["row"], 291);
  EXPECT_EQ(filled["time_gaps"][1]["missing"], 3);
  EXPECT_EQ(filled["rejected"], (10 + 1) + (3 + 1));
  EXPECT_EQ(filled["samples_estimation"], 400);
  EXPECT_NEAR(filled["theta"][0].get<double>(), -0.7, 1e-6);
  EXPECT_NEAR(filled["theta"][1].get<double>(), 0.5, 1e-6);

  const nlohmann::json reported = RealFileFitJson(path + kRealFileArx);
  ASSERT_EQ(reported["time_gaps"].size(), 2u);
  EXPECT_EQ(reported["time_gaps"][0]["filled"], 0);
  EXPECT_EQ(reported["samples_estimation"], 387);
  EXPECT_GT(std::abs(reported["theta"][0].get<double>() + 0.7), 1e-3);

  const CliResult text = RunCli("fit " + path + kRealFileArx);
  ASSERT_EQ(text.exit_code, 0) << text.err;
  EXPECT_NE(text.out.find("time column 't': 2 gaps (steps above 1.5 x the median step 0.1; 13 samples missing; "
                          "--missing fills them as missing samples): row 151 (14.9 -> 16), row 291 (29.9 -> 30.3)"),
            std::string::npos)
      << text.out;
  // No gap: an empty list; t read by the model: not checked.
  EXPECT_EQ(RealFileFitJson(WriteFile("rf_nogap.csv", RealFileText(r, ",")) + kRealFileArx)["time_gaps"],
            nlohmann::json::array());
  EXPECT_TRUE(RealFileFitJson(path + " --output y --regressors t,u --split 1")["time_gaps"].is_null());
}

TEST(RealFiles, TimeThatDoesNotIncreaseIsAnError) {
  ExpectCliError(
      "fit " + WriteFile("rf_back.csv", "t,u,y\n0.1,1,2\n# c\n0.2,2,3\n0.3,1,2\n0.2,3,4\n0.5,1,1\n") + kRealFileArx,
      "rf_back.csv:6: time column 't' does not increase: 0.2 after 0.3");
  ExpectCliError("fit " + WriteFile("rf_same.csv", "time,u,y\n1,1,2\n2,2,3\n2,1,2\n3,1,1\n") + kRealFileArx,
                 "rf_same.csv:4: time column 'time' does not increase: 2 after 2");
  // A gap longer than the record is not filled.
  ExpectCliError("fit " + WriteFile("rf_long_gap.csv", "t,u,y\n0,1,2\n1,2,3\n2,1,2\n1000,1,1\n1001,2,2\n") +
                     kRealFileArx + " --missing",
                 "rf_long_gap.csv:5: time column 't' jumps from 2 to 1000");
}

#if IDENT_HAVE_MATIO
// A .mat file (v5 and v7.3) of the record's vectors fits as its CSV does, bit for bit.
TEST(RealFiles, MatFilesFitAsTheirCsv) {
  const RealFileRecord r = RealFileNoiseless(200, 0.7, 0.5);
  const nlohmann::json csv = RealFileFitJson(WriteFile("rf_mat.csv", RealFileText(r, ",")) + kRealFileArx);
  for (const mat_ft version : {MAT_FT_MAT5, MAT_FT_MAT73}) {
    const std::string path = testing::TempDir() + (version == MAT_FT_MAT5 ? "/rf_v5.mat" : "/rf_v73.mat");
    testing::WriteMatFile(path, version, {{"t", {200, 1}, r.t}, {"u", {200, 1}, r.u}, {"y", {1, 200}, r.y}});
    const nlohmann::json mat = RealFileFitJson(path + kRealFileArx);
    EXPECT_EQ(mat["theta"], csv["theta"]) << path;
    EXPECT_EQ(mat["time_gaps"], nlohmann::json::array()) << path;
  }
  ExpectCliError("fit " + WriteFile("rf_bad.mat", "not a mat file") + kRealFileArx, "rf_bad.mat' as a MATLAB file");
}
#endif

}  // namespace
}  // namespace ident
