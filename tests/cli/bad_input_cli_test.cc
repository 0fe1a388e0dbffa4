// The bad-input table of docs/reference/cli.md, one test per row: what `ident` is given, the one line
// it prints on stderr ("ident: error: ..."), and its exit code (1 bad data/options, 2 usage).
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "tests/cli/scaled_dryer.h"
#include "tests/support/cli.h"
#include "tests/support/test_data.h"

namespace ident::testing {
namespace {

const std::string kArx = " --output y --input u --na 2 --nb 2 --nk 3";

std::string Repeat(const std::string& header, int rows, std::string (*row)(int)) {
  std::string csv = header + "\n";
  for (int i = 0; i < rows; ++i) csv += row(i) + "\n";
  return csv;
}

TEST(BadInput, MissingFile) {
  ExpectCliError("fit /nonexistent/x.csv" + kArx, "cannot open '/nonexistent/x.csv': No such file or directory");
}

TEST(BadInput, UnreadableFileIsADirectory) {
  const std::string dir = TempDir() + "/adir";
  std::filesystem::create_directories(dir);
  ExpectCliError("fit " + dir + kArx, "cannot read '" + dir + "': it is a directory");
}

TEST(BadInput, EmptyFile) {
  ExpectCliError("fit " + WriteFile("empty.csv", "") + kArx, "empty.csv: the file is empty");
}

TEST(BadInput, BlankLinesOnlyIsEmpty) {
  ExpectCliError("fit " + WriteFile("blank.csv", "\n  \r\n\n") + kArx, "blank.csv: the file is empty");
}

TEST(BadInput, HeaderOnly) {
  ExpectCliError("fit " + WriteFile("header.csv", "t,u,y\n") + kArx, "header.csv: no data rows after the header");
}

TEST(BadInput, RaggedRowShort) {
  ExpectCliError("fit " + WriteFile("ragged.csv", "t,u,y\n0,1,2\n1,2\n") + kArx,
                 "ragged.csv:3: row has 2 fields; the header has 3");
}

TEST(BadInput, RaggedRowLongLateInTheFile) {
  // The bad row sits in the validation part: still reported before any result.
  std::string csv = ReadFile(DatasetPath("dryer.csv"));
  csv += "1001,1,2,3\n";
  ExpectCliError("fit " + WriteFile("ragged_late.csv", csv) + kArx,
                 "ragged_late.csv:1002: row has 4 fields; the header has 3");
}

TEST(BadInput, FailedFitLeavesNoPartialTrace) {
  std::string csv = ReadFile(DatasetPath("dryer.csv"));
  csv += "1001,1,2,3\n";
  const std::string trace = TempDir() + "/failed_trace.csv";
  std::filesystem::remove(trace);  // from an earlier run
  ExpectCliError("fit " + WriteFile("ragged_trace.csv", csv) + kArx + " --trace " + trace,
                 "ragged_trace.csv:1002: row has 4 fields; the header has 3");
  EXPECT_FALSE(std::filesystem::exists(trace));
}

TEST(BadInput, NonNumericCell) {
  ExpectCliError("fit " + WriteFile("text.csv", "t,u,y\n0,1,2\n1,x1,2\n") + kArx,
                 "text.csv:3: column 2 ('u'): 'x1' is not a number");
}

TEST(BadInput, EmptyCell) {
  ExpectCliError("fit " + WriteFile("hole.csv", "t,u,y\n0,,2\n") + kArx, "hole.csv:2: column 2 ('u') is empty");
}

TEST(BadInput, NanCell) {
  ExpectCliError("fit " + WriteFile("nan.csv", "t,u,y\n0,1,2\n1,NaN,3\n") + kArx,
                 "nan.csv:3: column 2 ('u'): 'NaN' is not a finite number (pass --missing");
}

TEST(BadInput, InfCell) {
  ExpectCliError("fit " + WriteFile("inf.csv", "t,u,y\n0,1,-inf\n") + kArx,
                 "inf.csv:2: column 3 ('y'): '-inf' is not a finite number");
}

TEST(BadInput, CellBeyondDoubleRange) {
  ExpectCliError("fit " + WriteFile("e309.csv", "t,u,y\n0,1e309,1\n") + kArx,
                 "e309.csv:2: column 2 ('u'): '1e309' is out of the range of double");
}

TEST(BadInput, ValuesNear1e308AreRefusedNotTurnedIntoInf) {
  ExpectCliError("fit " + ScaledDryer("dryer_e300.csv", 1e300) + kArx,
                 "none of the 496 samples of the estimation part could be used");
}

TEST(BadInput, OneValueNear1e308SpoilsTheMeanAndIsRefused) {
  std::string csv = ReadFile(DatasetPath("dryer.csv"));
  const std::size_t row = csv.find("\n7.92,");  // row 100, in the estimation part
  ASSERT_NE(row, std::string::npos);
  const std::size_t comma = csv.find(',', row + 1), next = csv.find(',', comma + 1);
  csv.replace(comma + 1, next - comma - 1, "1.7e308");
  ExpectCliError("fit " + WriteFile("dryer_one.csv", csv) + kArx, "could be used (all missing, or too large");
}

TEST(BadInput, ValuesNear1e308OfBothSignsOverflowTheMean) {
  const std::string path = WriteFile("alt.csv", Repeat("t,u,y", 40, [](int i) {
                                       return fmt::format("{},{},{}", i, i % 2 ? 1.7e308 : -1.7e308, std::sin(i));
                                     }));
  ExpectCliError("fit " + path + " --output y --input u --na 1 --nb 1 --nk 1", "the mean of column 'u' overflows");
}

// Squares of 1e150 are still finite: the result must be correct, not inf/NaN. ARX parameters do not
// change when u and y are scaled alike, so θ must equal the unscaled fit's; fit % too.
TEST(BadInput, ValuesNear1e150GiveTheSameModelAsUnscaledData) {
  const CliResult base = RunCli("fit dryer" + kArx + " --json");
  const CliResult big = RunCli("fit " + ScaledDryer("dryer_e150.csv", 1e150) + kArx + " --json");
  ASSERT_EQ(base.exit_code, 0) << base.err;
  ASSERT_EQ(big.exit_code, 0) << big.err;
  const auto b = nlohmann::json::parse(base.out), l = nlohmann::json::parse(big.out);
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(l["theta"][i].get<double>(), b["theta"][i].get<double>(), 1e-9) << i;
  EXPECT_NEAR(l["fit_percent"]["one_step"].get<double>(), b["fit_percent"]["one_step"].get<double>(), 1e-9);
  EXPECT_NEAR(l["rms"]["one_step"].get<double>() / 1e150, b["rms"]["one_step"].get<double>(), 1e-12);
}

// Values near 1e-150 have squares near 1e-300, far below the default flat prior's information 1e-12:
// the estimate would be the prior's (θ ≈ 1e-286, found by this test) — refused with a clear message.
TEST(BadInput, ValuesNear1em150AreRefusedInsteadOfReturningThePrior) {
  ExpectCliError("fit " + ScaledDryer("dryer_em150.csv", 1e-150) + kArx,
                 "over the estimation part, too small against the default flat prior (values near 1e-150?)");
}

// Ordinary small units (dryer × 3e-5: sums of squares ~1e-7): the default priors follow the data's scale
// (RLS: RegressionPrior::Flat(mean squares); Kárný–Hangos: the data-driven start-up prior), so every
// estimator returns the unscaled fit's θ — ARX θ does not change when u and y are scaled alike — instead
// of refusing the record (before: "too small against the default flat prior") or biasing θ towards the prior.
TEST(BadInput, SmallUnitsGiveTheSameModelAsUnscaledData) {
  const std::string small = ScaledDryer("dryer_small.csv", 3e-5);
  for (const std::string estimator : {"rls", "cauchy", "student:3"}) {
    const CliResult base = RunCli("fit dryer" + kArx + " --estimator " + estimator + " --json");
    const CliResult scaled = RunCli("fit " + small + kArx + " --estimator " + estimator + " --json");
    ASSERT_EQ(base.exit_code, 0) << base.err;
    ASSERT_EQ(scaled.exit_code, 0) << estimator << ": " << scaled.err;
    const auto b = nlohmann::json::parse(base.out), s = nlohmann::json::parse(scaled.out);
    for (int i = 0; i < 4; ++i)
      EXPECT_NEAR(s["theta"][i].get<double>(), b["theta"][i].get<double>(), 1e-9) << estimator << " theta " << i;
    EXPECT_NEAR(s["fit_percent"]["one_step"].get<double>(), b["fit_percent"]["one_step"].get<double>(), 1e-9)
        << estimator;
  }
}

// Orders far beyond any record are refused from the structure alone — before (before: 7.8 GB were
// allocated, then "std::bad_alloc") and without integer overflow (before: nb = INT_MAX wrapped around).
TEST(BadInput, HugeOrdersAreRefusedBeforeAllocating) {
  ExpectCliError("fit dryer --output y --input u --na 1000000000",
                 "the model has 1000000002 parameters; need at most 10000");
  ExpectCliError("fit dryer --output y --input u --nb 2147483647",
                 "nk + nb = 2147483648 for input 1; need at most 10000000");
}

TEST(BadInput, DofContradictingTheEstimatorSpecNamesIt) {
  ExpectCliError("fit dryer" + kArx + " --estimator student:3 --dof 5", "--dof 5 contradicts estimator 'student:3'");
}

// A spec key and its option set the same field: either one alone takes effect, the same value twice is
// accepted, and two different values are refused, naming both.
TEST(BadInput, SpecKeysAndTheirOptionsSetTheSameField) {
  const auto theta = [](const std::string& args) {
    const CliResult r = RunCli("fit dryer" + kArx + " " + args + " --json");
    EXPECT_EQ(r.exit_code, 0) << args << ": " << r.err;
    return r.exit_code == 0 ? nlohmann::json::parse(r.out)["theta"] : nlohmann::json();
  };
  for (const auto& [spec, option] :
       {std::pair<std::string, std::string>{"rls:forgetting=0.9", "rls --forgetting 0.9"},
        {"cauchy:delta=0", "cauchy --delta 0"},
        {"cauchy:lock_in_window=50,lock_in_threshold=0.5", "cauchy --lock-in-window 50 --lock-in-threshold 0.5"}}) {
    const auto by_spec = theta("--estimator " + spec), by_option = theta("--estimator " + option);
    const auto plain = theta("--estimator " + option.substr(0, option.find(' ')));
    ASSERT_EQ(by_spec.size(), 4u) << spec;
    EXPECT_EQ(by_spec, by_option) << spec;
    EXPECT_EQ(theta("--estimator " + spec + " " + option.substr(option.find(' ') + 1)), by_spec) << spec;
    if (spec != "cauchy:lock_in_window=50,lock_in_threshold=0.5") {
      EXPECT_NE(by_spec, plain) << spec;
    }
  }
  ExpectCliError("fit dryer" + kArx + " --estimator rls:forgetting=0.9 --forgetting 0.99",
                 "--forgetting 0.99 contradicts estimator 'rls:forgetting=0.9'");
  ExpectCliError("fit dryer" + kArx + " --estimator cauchy:delta=0 --delta 1",
                 "--delta 1 contradicts estimator 'cauchy:delta=0'");
  ExpectCliError("fit dryer" + kArx + " --estimator cauchy:lock_in_window=50 --lock-in-window 60",
                 "--lock-in-window 60 contradicts estimator 'cauchy:lock_in_window=50'");
  ExpectCliError("fit dryer" + kArx + " --estimator cauchy:lock_in_window=5000",
                 "estimator 'cauchy:lock_in_window=5000': lock_in_window 5000 exceeds the estimation part's 500 rows");
}

// ident orders ranks ARX structures by batch least squares: a recursion's setting in the spec would be
// ignored there, so it is refused.
TEST(BadInput, OrdersRefusesRecursionSettingsForItsLeastSquaresGrid) {
  ExpectCliError("orders dryer --output y --input u --na 1:2 --nb 1:2 --nk 3 --estimator rls:forgetting=0.9",
                 "orders --estimator 'rls:forgetting=0.9': forgetting does not apply to the ARX grid's least-squares "
                 "fits (give plain rls)");
}

TEST(BadInput, InadmissibleForgettingIsBlamedOnTheForgettingFactor) {
  ExpectCliError("fit dryer" + kArx + " --estimator cauchy --forgetting 0.5",
                 "forgetting = 0.5 is inadmissible with nu0 = 6: the first step has nu(1) = forgetting*nu0 + 1 = 4");
}

// Usage errors are one line too, and an unknown subcommand is named.
TEST(BadInput, UnknownSubcommandIsNamedOnOneLine) {
  const CliResult r = RunCli("bogus");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.err.rfind("ident: error: unknown subcommand 'bogus' (known: fit datasets", 0), 0u) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
}

TEST(BadInput, ConstantInputColumn) {
  const std::string path =
      WriteFile("const.csv", Repeat("t,u,y", 50, [](int i) { return fmt::format("{},1.5,{}", i, std::sin(0.3 * i)); }));
  ExpectCliError(
      "fit " + path + " --output y --input u --na 1 --nb 1 --nk 1",
      "regressor 'b1' is identically zero over the estimation part (a constant column after detrending?); the "
      "model is not identifiable");
}

TEST(BadInput, CollinearRegressors) {
  const std::string path = WriteFile("collinear.csv", Repeat("x1,x2,y", 50, [](int i) {
                                       return fmt::format("{},{},{}", std::sin(i), 2 * std::sin(i), i % 7);
                                     }));
  ExpectCliError("fit " + path + " --output y --regressors x1,x2",
                 "the regressors are collinear over the estimation part");
}

TEST(BadInput, OrdersTooLargeForTheRecord) {
  ExpectCliError("fit gas_furnace --output y --input u --na 100 --nb 50 --nk 3",
                 "the estimation part has 148 rows; ARX(100,50,3) with 150 parameters needs at least 251");
}

TEST(BadInput, UnknownEstimator) {
  ExpectCliError("fit dryer" + kArx + " --estimator nonesuch", "unknown estimator 'nonesuch'");
}

TEST(BadInput, UnknownColumn) {
  ExpectCliError("fit dryer --output y --input q --na 2 --nb 2 --nk 3", "no column 'q' (columns: t, u, y)");
}

TEST(BadInput, ForgettingAboveOne) {
  ExpectCliError("fit dryer" + kArx + " --forgetting 1.5", "forgetting = 1.5; need 0 < forgetting <= 1");
}
TEST(BadInput, ForgettingZero) {
  ExpectCliError("fit dryer" + kArx + " --forgetting 0", "forgetting = 0; need 0 < forgetting <= 1");
}
TEST(BadInput, ForgettingNegative) { ExpectCliError("fit dryer" + kArx + " --forgetting -0.5", "forgetting = -0.5"); }
TEST(BadInput, ForgettingNan) { ExpectCliError("fit dryer" + kArx + " --forgetting nan", "forgetting = nan"); }
TEST(BadInput, ForgettingNotANumberIsAUsageError) {
  ExpectCliError("fit dryer" + kArx + " --forgetting abc", "--forgetting", 2);
}

TEST(BadInput, PriorDegreesZero) {
  ExpectCliError("fit dryer" + kArx + " --nu0 0 --vy0 1 --vz0 1", "nu0 = 0; need a positive number of prior degrees");
}
TEST(BadInput, PriorDegreesNegative) { ExpectCliError("fit dryer" + kArx + " --nu0 -1 --vy0 1 --vz0 1", "nu0 = -1"); }
TEST(BadInput, NegativePriorOutputVariance) {
  ExpectCliError("fit dryer" + kArx + " --nu0 5 --vy0 -1 --vz0 1", "vy0 = -1; need a positive prior output variance");
}
TEST(BadInput, NegativePriorRegressorVariance) {
  ExpectCliError("fit dryer" + kArx + " --nu0 5 --vy0 1 --vz0 -2",
                 "vz0 = -2; need a positive prior regressor variance");
}

TEST(BadInput, DofForAnEstimatorWithoutOne) {
  ExpectCliError("fit dryer" + kArx + " --dof 0", "dof = 0 does not apply to estimator 'rls'");
}

TEST(BadInput, SplitOutOfRange) { ExpectCliError("fit dryer" + kArx + " --split 0", "split = 0; need 0 < split <= 1"); }

TEST(BadInput, NegativeOrder) { ExpectCliError("fit dryer --output y --input u --na -1", "na = -1; need na >= 0"); }

TEST(BadInput, MalformedPriorJson) {
  ExpectCliError("fit dryer" + kArx + " --prior " + WriteFile("bad.json", "{\"nu0\": 5, "), "bad.json: not valid JSON");
}

TEST(BadInput, PriorJsonOfTheWrongDimension) {
  ExpectCliError("fit dryer" + kArx + " --prior " + WriteFile("dim.json", "{\"nu0\": 5, \"V0\": [[1,0],[0,1]]}"),
                 "dim.json: V0 has 2 rows; the model needs 5x5 (rho = 4, y first)");
}

TEST(BadInput, PriorJsonNotPositiveDefinite) {
  ExpectCliError(
      "fit dryer --output y --regressors u --prior " + WriteFile("npd.json", "{\"nu0\": 5, \"V0\": [[1,2],[2,1]]}"),
      "npd.json: prior matrix V is not positive definite");
}

TEST(BadInput, UnknownOptionIsAUsageError) { ExpectCliError("fit dryer" + kArx + " --bogus", "--bogus", 2); }

// The record's length is checked before the estimator (whose prior costs O(rho^3)) is built: the
// length error comes even where the estimator name is bad, which is checked only when it is built.
TEST(BadInput, OrdersTooLargeForTheRecordAreRefusedBeforeTheEstimatorIsBuilt) {
  ExpectCliError("fit dryer --output y --input u --na 2000",
                 "the estimation part has 500 rows; ARX(2000,2,1) with 2002 parameters needs at least 4003");
  ExpectCliError("fit dryer --output y --input u --na 5000 --estimator nonesuch",
                 "the estimation part has 500 rows; ARX(5000,2,1) with 5002 parameters needs at least 10003");
  ExpectCliError("fit dryer --output y --input u --na 2000 --prior " + TempDir(), "the estimation part has 500 rows");
}

TEST(BadInput, ValuesNear1em200AreTooSmallNotAConstantColumn) {
  const std::string path = ScaledDryer("dryer_1em200.csv", 1e-200);
  ExpectCliError("fit " + path + kArx,
                 "dryer_1em200.csv: regressor 'a1' has sum of squares 0 over the estimation part: its values "
                 "(largest 1.64e-200) are too small");
  ExpectCliError("fit " + path + kArx,
                 "are too small to square in double precision (values near 1e-200?); rescale the data");
}

TEST(BadInput, TinyDofIsBlamedOnTheDof) {
  ExpectCliError("fit dryer" + kArx + " --estimator student --dof 1e-300",
                 "dof = 1e-300 is too small: nu_hard >= (k+3-delta)/k = 2e+300 exceeds the first step's nu(1) = 6");
}

TEST(BadInput, PriorFileIsADirectory) {
  const std::string dir = TempDir() + "/prior_dir";
  std::filesystem::create_directories(dir);
  ExpectCliError("fit dryer" + kArx + " --prior " + dir, "cannot read '" + dir + "': it is a directory");
}

TEST(BadInput, UnknownKeyInThePriorJsonIsNamed) {
  ExpectCliError("fit dryer --output y --regressors u --prior " +
                     WriteFile("unknown_key.json", R"({"nu0": 5, "V0": [[1, 0], [0, 1]], "Vo": 1})"),
                 R"(unknown_key.json: unknown key "Vo" (known: nu0, V0))");
}

TEST(BadInput, DeltaForAnEstimatorWithoutOne) {
  ExpectCliError("fit dryer" + kArx + " --delta 0", "delta = 0 does not apply to estimator 'rls'");
  ExpectCliError("fit dryer" + kArx + " --estimator huber --delta 1", "delta = 1 does not apply to estimator 'huber'");
  ExpectCliError("fit dryer" + kArx + " --estimator cauchy --delta 2", "delta = 2; need 0 or 1");
}

TEST(BadInput, LockInWindowBeyondTheLimit) {
  ExpectCliError("fit dryer" + kArx + " --estimator cauchy --lock-in-window 2147483647",
                 "--lock-in-window 2147483647 exceeds the estimation part's 500 rows: the monitor could never fill; "
                 "need at most 500");
  ExpectCliError("fit dryer" + kArx + " --estimator cauchy --split 1 --lock-in-window 1001",
                 "--lock-in-window 1001 exceeds the estimation part's 1000 rows");
  // The whole estimation part is the longest window.
  const CliResult r = RunCli("fit dryer" + kArx + " --estimator cauchy --lock-in-window 500 --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["lock_in"]["window"].get<int>(), 500);
  EXPECT_EQ(j["lock_in"]["flagged"].get<int>(), 0);
}

TEST(BadInput, PlusMinusIsNotANumber) {
  ExpectCliError("fit " + WriteFile("plus_minus.csv", "t,u,y\n0,+-5,1\n") + kArx,
                 "plus_minus.csv:2: column 2 ('u'): '+-5' is not a number");
}

TEST(BadInput, NulByteInACellIsReported) {
  ExpectCliError("fit " +
                     WriteFile("nul.csv", std::string("t,u,y\n0,1\0"
                                                      "2,3\n",
                                                      14)) +
                     kArx,
                 "nul.csv:2: column 2 ('u'): contains a NUL byte");
}

TEST(BadInput, BlankLineInsideTheData) {
  std::string csv = ReadFile(DatasetPath("dryer.csv"));
  const std::size_t at = csv.find("\n", csv.size() / 2) + 1;
  const long line = std::count(csv.begin(), csv.begin() + static_cast<long>(at), '\n') + 1;
  ASSERT_GT(line, 400);
  csv.insert(at, "\n");
  ExpectCliError("fit " + WriteFile("gap.csv", csv) + kArx,
                 fmt::format("gap.csv:{}: blank line inside the data (a gap in the record?)", line));
}

TEST(BadInput, LineLongerThanTheLimit) {
  if (std::filesystem::exists("/dev/zero"))
    ExpectCliError("fit /dev/zero" + kArx, "/dev/zero:1: line longer than 1048576 bytes");
  ExpectCliError("fit " + WriteFile("long_line.csv", "t,u,y\n0," + std::string(2 << 20, '1') + ",3\n") + kArx,
                 "long_line.csv:2: line longer than 1048576 bytes");
}

TEST(BadInput, LongCellIsEchoedTruncated) {
  const std::string path = WriteFile("long_cell.csv", "t,u,y\n0," + std::string(100000, 'x') + ",3\n");
  const CliResult r = RunCli("fit " + path + kArx);
  ExpectCliError("fit " + path + kArx,
                 "long_cell.csv:2: column 2 ('u'): '" + std::string(32, 'x') + "...' (100000 bytes) is not a number");
  EXPECT_LT(r.err.size(), 300u) << r.err.size();
}

TEST(BadInput, TooManyColumns) {
  std::string header = "y";
  for (int j = 1; j <= 100000; ++j) header += fmt::format(",c{}", j);
  ExpectCliError("fit " + WriteFile("too_wide.csv", header + "\n") + kArx,
                 "too_wide.csv:1: the header has 100001 columns; at most 100000 are supported");
}

// Old Mac files (CR line ends) are read as they are meant: the same model as the LF file.
TEST(BadInput, CrOnlyLineEndsGiveTheSameModelAsLf) {
  std::string cr = ReadFile(DatasetPath("dryer.csv"));
  cr.erase(std::remove(cr.begin(), cr.end(), '\r'), cr.end());
  std::replace(cr.begin(), cr.end(), '\n', '\r');
  const CliResult a = RunCli("fit dryer" + kArx + " --json");
  const CliResult b = RunCli("fit " + WriteFile("dryer_cr.csv", cr) + kArx + " --json");
  ASSERT_EQ(a.exit_code, 0) << a.err;
  ASSERT_EQ(b.exit_code, 0) << b.err;
  const auto ja = nlohmann::json::parse(a.out), jb = nlohmann::json::parse(b.out);
  EXPECT_EQ(jb["samples_estimation"].get<int>(), 500);
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(jb["theta"][i].get<double>(), ja["theta"][i].get<double>(), 1e-12) << i;
  EXPECT_NEAR(jb["fit_percent"]["one_step"].get<double>(), ja["fit_percent"]["one_step"].get<double>(), 1e-9);
}

}  // namespace
}  // namespace ident::testing
