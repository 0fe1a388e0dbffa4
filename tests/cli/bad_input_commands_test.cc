// The bad-input table of docs/reference/cli.md for the commands other than `ident fit` (compare,
// datasets, mems, smooth, logcondens), one test per row: what `ident` is given, the one line it prints
// on stderr ("ident: error: ..."), empty stdout, and the exit code (1 bad data/options, 2 usage).
// Rows about the data file run every command that reads one (compare, smooth, logcondens) on the
// same file, whose header u,x,y,z serves all three (compare: y on u; smooth: z; logcondens: x).
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <string>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "tests/cli/scaled_dryer.h"
#include "tests/support/cli.h"
#include "tests/support/test_data.h"

namespace ident::testing {
namespace {

const std::string kCompare = " --output y --input u --na 1 --nb 1 --nk 1 --estimators rls --outliers none";
const std::string kGoodModel =
    R"({"F": [[1]], "H": [[1]], "initial": {"penalty": "quadratic", "covariance": 1},
        "process": {"penalty": "quadratic", "covariance": 1}, "measurement": {"penalty": "huber", "kappa": 1}})";

std::string Quote(const std::string& path) { return "'" + path + "'"; }

// Runs compare, smooth and logcondens on `csv` and expects exit 1 with `needle` in each message.
void ExpectEveryReaderRejects(const std::string& csv, const std::string& needle) {
  ExpectCliError("compare " + Quote(csv) + kCompare, needle);
  ExpectCliError("smooth --model " + Quote(WriteFile("good_model.json", kGoodModel)) + " " + Quote(csv), needle);
  ExpectCliError("logcondens " + Quote(csv), needle);
}

std::string Model(const std::string& initial, const std::string& process = R"({"penalty": "l1"})",
                  const std::string& measurement = R"({"penalty": "l1"})",
                  const std::string& fh = R"("F": [[1]], "H": [[1]])") {
  return WriteFile("model.json", "{" + fh + ", \"initial\": " + initial + ", \"process\": " + process +
                                     ", \"measurement\": " + measurement + "}");
}

std::string SmoothData() { return WriteFile("z.csv", "z\n0.5\n1.2\n3.1\n2.0\n"); }

void ExpectSmoothError(const std::string& model_path, const std::string& needle) {
  ExpectCliError("smooth --model " + Quote(model_path) + " " + Quote(SmoothData()), needle);
}

// ---- data files: compare, smooth, logcondens ------------------------------------------------------

TEST(BadInputCommands, MissingFile) {
  ExpectEveryReaderRejects("/nonexistent/x.csv", "cannot open '/nonexistent/x.csv'");
}

TEST(BadInputCommands, UnreadableFileIsADirectory) {
  const std::string dir = TempDir() + "/adir";
  std::filesystem::create_directories(dir);
  ExpectEveryReaderRejects(dir, "cannot read '" + dir + "': it is a directory");
}

TEST(BadInputCommands, EmptyFile) {
  ExpectEveryReaderRejects(WriteFile("empty.csv", ""), "empty.csv: the file is empty");
}

TEST(BadInputCommands, HeaderOnly) {
  ExpectEveryReaderRejects(WriteFile("header.csv", "u,x,y,z\n"), "header.csv: no data rows after the header");
}

TEST(BadInputCommands, RaggedRow) {
  ExpectEveryReaderRejects(WriteFile("ragged.csv", "u,x,y,z\n1,2,3,4\n1,2\n"),
                           "ragged.csv:3: row has 2 fields; the header has 4");
}

TEST(BadInputCommands, NonNumericCell) {
  ExpectEveryReaderRejects(WriteFile("text.csv", "u,x,y,z\n1,2,3,4\n1,x1,3,4\n"),
                           "text.csv:3: column 2 ('x'): 'x1' is not a number");
}

TEST(BadInputCommands, NanCell) {
  ExpectEveryReaderRejects(WriteFile("nan.csv", "u,x,y,z\n1,2,3,4\n1,NaN,3,4\n"),
                           "nan.csv:3: column 2 ('x'): 'NaN' is not a finite number");
}

TEST(BadInputCommands, InfCell) {
  ExpectEveryReaderRejects(WriteFile("inf.csv", "u,x,y,z\n1,2,3,-inf\n"),
                           "inf.csv:2: column 4 ('z'): '-inf' is not a finite number");
}

TEST(BadInputCommands, BlankLineInsideTheData) {
  ExpectEveryReaderRejects(WriteFile("gap.csv", "u,x,y,z\n1,1,2,3\n2,2,3,4\n\n3,3,4,5\n4,4,5,6\n"),
                           "gap.csv:4: blank line inside the data (a gap in the record?)");
}

TEST(BadInputCommands, NulByteInACell) {
  ExpectEveryReaderRejects(WriteFile("nul.csv", std::string("u,x,y,z\n1,1\0"
                                                            "5,2,3\n",
                                                            18)),
                           "nul.csv:2: column 2 ('x'): contains a NUL byte");
}

TEST(BadInputCommands, LineLongerThanTheLimit) {
  ExpectEveryReaderRejects(WriteFile("long_line.csv", "u,x,y,z\n1," + std::string(1 << 20, '2') + ",3,4\n"),
                           "long_line.csv:2: line longer than 1048576 bytes");
}

TEST(BadInputCommands, CellBeyondDoubleRange) {
  ExpectEveryReaderRejects(WriteFile("e309.csv", "u,x,y,z\n1,1e309,3,4\n"),
                           "e309.csv:2: column 2 ('x'): '1e309' is out of the range of double");
}

// ---- ident compare ----------------------------------------------------------------------------------

const std::string kCompareArx = " --output y --input u --na 2 --nb 2 --nk 3 --estimators rls";

TEST(BadInputCompare, ValuesNear1e308) {
  ExpectCliError("compare " + ScaledDryer("dryer_e300.csv", 1e300) + kCompareArx, "rescale the data");
}

TEST(BadInputCompare, ConstantInputColumn) {
  std::string csv = "u,y\n";
  for (int t = 0; t < 200; ++t) csv += fmt::format("3,{}\n", std::sin(0.1 * t));
  ExpectCliError(
      "compare " + WriteFile("const.csv", csv) + " --output y --input u --na 1 --nb 1 --nk 1 --estimators rls",
      "regressor 'b1' is identically zero over the estimation part");
}

TEST(BadInputCompare, CollinearRegressors) {
  std::string csv = "x1,x2,y\n";
  for (int t = 0; t < 200; ++t)
    csv += fmt::format("{},{},{}\n", std::sin(0.3 * t), 2 * std::sin(0.3 * t), std::cos(0.2 * t));
  ExpectCliError("compare " + WriteFile("collinear.csv", csv) + " --output y --regressors x1,x2 --estimators rls",
                 "the regressors are collinear over the estimation part");
}

TEST(BadInputCompare, OrdersTooLargeForTheRecord) {
  ExpectCliError("compare gas_furnace --estimators rls --na 60 --nb 60", "the estimation part has 148 rows");
}

TEST(BadInputCompare, EmptyEstimatorName) {
  ExpectCliError("compare dryer --estimators ''", "--estimators: an empty estimator name");
}

TEST(BadInputCompare, EmptyNameInsideTheEstimatorList) {
  ExpectCliError("compare dryer --estimators rls,,cauchy", "--estimators: an empty estimator name in 'rls,,cauchy'");
  ExpectCliError("compare dryer --estimators rls, --estimators cauchy",
                 "--estimators: an empty estimator name in 'rls,'");
}

TEST(BadInputCompare, LockInWindowBeyondTheLimit) {
  ExpectCliError("compare dryer --estimators rls,cauchy --lock-in-window 1000001",
                 "--lock-in-window 1000001 exceeds the estimation part's 500 rows: the monitor could never fill; "
                 "need at most 500");
}

TEST(BadInputCompare, UnknownEstimator) {
  ExpectCliError("compare dryer --estimators rls,nonesuch", "unknown estimator 'nonesuch'");
}

TEST(BadInputCompare, UnknownColumn) {
  ExpectCliError("compare dryer --estimators rls --output y --input q", "no column 'q'");
}

TEST(BadInputCompare, UnknownDataset) { ExpectCliError("compare nonesuch", "no file or bundled dataset 'nonesuch'"); }

TEST(BadInputCompare, ForgettingAboveOne) {
  ExpectCliError("compare dryer --estimators rls --forgetting 1.5", "forgetting = 1.5; need 0 < forgetting <= 1");
}

TEST(BadInputCompare, ForgettingZero) {
  ExpectCliError("compare dryer --estimators rls --forgetting 0", "forgetting = 0; need 0 < forgetting <= 1");
}

TEST(BadInputCompare, PriorDegreesZero) {
  ExpectCliError("compare dryer --estimators rls --nu0 0 --vy0 1 --vz0 1",
                 "nu0 = 0; need a positive number of prior degrees");
}

TEST(BadInputCompare, NegativePriorVariance) {
  ExpectCliError("compare dryer --estimators rls --nu0 5 --vy0 -1 --vz0 1",
                 "vy0 = -1; need a positive prior output variance");
}

TEST(BadInputCompare, DofZero) { ExpectCliError("compare dryer --estimators student:0", "dof = 0"); }

TEST(BadInputCompare, DofNegative) { ExpectCliError("compare dryer --estimators student --dof -2", "dof = -2"); }

TEST(BadInputCompare, MalformedPriorJson) {
  ExpectCliError("compare dryer --estimators rls --prior " + WriteFile("bad.json", "{\"nu0\": 5, \"V0\": [[1,"),
                 "bad.json: not valid JSON");
}

TEST(BadInputCompare, PriorJsonOfTheWrongDimension) {
  ExpectCliError(
      "compare dryer --estimators rls --prior " + WriteFile("dim.json", R"({"nu0": 5, "V0": [[1, 0], [0, 1]]})"),
      "dim.json: V0 has 2 rows; the model needs 5x5");
}

TEST(BadInputCompare, BadOutlierSpec) {
  ExpectCliError("compare dryer --estimators rls --outliers 2:20", "RATE = 2; need 0 <= RATE < 1");
}

TEST(BadInputCompare, TrialsZero) { ExpectCliError("compare dryer --estimators rls --trials 0", "--trials = 0"); }

TEST(BadInputCompare, UnknownOptionIsAUsageError) { ExpectCliError("compare dryer --bogus", "--bogus", 2); }

// ---- ident datasets ---------------------------------------------------------------------------------

// Runs `args` with IDENT_DATASETS set to `dir` (inherited by the child process).
void ExpectDatasetsError(const std::string& dir, const std::string& args, const std::string& needle) {
  setenv("IDENT_DATASETS", dir.c_str(), 1);
  ExpectCliError(args, needle);
  unsetenv("IDENT_DATASETS");
}

TEST(BadInputDatasets, MissingIndex) {
  ExpectDatasetsError("/nonexistent", "datasets", "cannot open the dataset index '/nonexistent/index.json'");
}

TEST(BadInputDatasets, MalformedIndex) {
  const std::string dir = TempDir() + "/bad_index";
  std::filesystem::create_directories(dir);
  WriteFile("bad_index/index.json", R"({"datasets": [{"name": "a"}]})");
  ExpectDatasetsError(dir, "datasets", "malformed dataset index");
}

TEST(BadInputDatasets, IndexNamesAMissingFile) {
  const std::string dir = TempDir() + "/lost_file";
  std::filesystem::create_directories(dir);
  WriteFile("lost_file/index.json", R"({"datasets": [{"name": "a", "file": "a.csv",
      "structure": {"output": "y", "input": ["u"], "na": 1, "nb": [1], "nk": [1]}}]})");
  ExpectDatasetsError(dir, "datasets", "cannot open '" + dir + "/a.csv'");
}

TEST(BadInputDatasets, UnknownDatasetName) {
  ExpectCliError("fit nonesuch --output y --input u", "no file or bundled dataset 'nonesuch'");
}

TEST(BadInputDatasets, UnknownOptionIsAUsageError) { ExpectCliError("datasets --bogus", "--bogus", 2); }

// ---- ident mems ---------------------------------------------------------------------------------------

TEST(BadInputMems, TooFewSteps) { ExpectCliError("mems --steps 10", "steps = 10; need 100..1000000"); }

TEST(BadInputMems, StepsBeyondTheLimit) {
  ExpectCliError("mems --steps 2147483647", "steps = 2147483647; need 100..1000000");
}

TEST(BadInputMems, TMeanNotPositive) { ExpectCliError("mems --t-mean 1,-1", "--t-mean value -1 must be > 0"); }

TEST(BadInputMems, TMeanNan) { ExpectCliError("mems --t-mean nan", "--t-mean value nan must be > 0"); }

TEST(BadInputMems, TMeanBelowTenSamplingPeriods) {
  ExpectCliError("mems --steps 400 --grid-points 16 --t-mean 1,0.05", "t_target = 0.05; need >= 10 h = 0.1");
}

TEST(BadInputMems, SamplingPeriodNotPositive) { ExpectCliError("mems --h 0", "h = 0; need 0 < h < 1"); }

TEST(BadInputMems, SamplingPeriodNan) { ExpectCliError("mems --h nan", "h = nan; need 0 < h < 1"); }

TEST(BadInputMems, GridTooCoarse) { ExpectCliError("mems --grid-points 4", "grid_points = 4; need 16..1024"); }
TEST(BadInputMems, EpWindowZero) { ExpectCliError("mems --ep-window 0", "ep_window = 0; need 1..4096"); }

TEST(BadInputMems, UnwritableCsvIsReportedBeforeTheStudyRuns) {
  ExpectCliError("mems --steps 400 --grid-points 16 --t-mean 1 --csv /nonexistent/dir/t.csv",
                 "cannot write --csv file '/nonexistent/dir/t.csv'");
}

TEST(BadInputMems, UnwritableTraceIsReportedBeforeTheStudyRuns) {
  ExpectCliError("mems --steps 400 --grid-points 16 --t-mean 1 --trace /nonexistent/dir/t.csv",
                 "cannot write --trace file '/nonexistent/dir/t.csv'");
}

TEST(BadInputMems, UnknownPlotFormatIsReportedBeforeTheStudyRuns) {
  ExpectCliError("mems --steps 400 --grid-points 16 --t-mean 1 --plot " + TempDir() + "/fig.unknown", "fig.unknown");
}

TEST(BadInputMems, StepsNotANumberIsAUsageError) { ExpectCliError("mems --steps abc", "--steps", 2); }

TEST(BadInputMems, UnknownOptionIsAUsageError) { ExpectCliError("mems --no-such-option", "--no-such-option", 2); }

// ---- ident smooth -------------------------------------------------------------------------------------

const std::string kF2H2 = R"("F": [[1, 1], [0, 1]], "H": [[1, 1]])";

TEST(BadInputSmooth, MissingModelFile) {
  ExpectCliError("smooth --model /nonexistent/m.json " + Quote(SmoothData()), "cannot open '/nonexistent/m.json'");
}

TEST(BadInputSmooth, ModelIsADirectory) {
  const std::string dir = TempDir() + "/model_dir";
  std::filesystem::create_directories(dir);
  ExpectCliError("smooth --model " + Quote(dir) + " " + Quote(SmoothData()),
                 "cannot read '" + dir + "': it is a directory");
}

TEST(BadInputSmooth, MalformedJson) {
  ExpectSmoothError(WriteFile("m.json", "{\"F\": [[1]"), "m.json: not valid JSON");
}

TEST(BadInputSmooth, ModelNotAnObject) {
  ExpectSmoothError(WriteFile("m.json", "[1, 2]"), "the model must be a JSON object");
}

TEST(BadInputSmooth, MissingKey) {
  ExpectSmoothError(WriteFile("m.json", R"({"F": [[1]], "H": [[1]]})"), "m.json: missing \"initial\"");
}

TEST(BadInputSmooth, UnknownKey) {
  ExpectSmoothError(WriteFile("m.json", R"({"F": [[1]], "H": [[1]], "G": 1})"), "unknown key \"G\"");
}

TEST(BadInputSmooth, FAndHDimensionsDisagree) {
  ExpectSmoothError(Model(R"({"penalty": "l1"})", R"({"penalty": "l1"})", R"({"penalty": "l1"})",
                          R"("F": [[1, 1], [0, 1]], "H": [[1, 1, 0]])"),
                    "F[0] is 2x2 but H has 3 columns");
}

TEST(BadInputSmooth, HRowsDisagreeWithTheDataColumns) {
  ExpectSmoothError(Model(R"({"penalty": "l1"})", R"({"penalty": "l1"})", R"({"penalty": "l1"})",
                          R"("F": [[1, 1], [0, 1]], "H": [[1, 1], [1, 0]])"),
                    "H has 2 rows but the data have 1 measurement columns");
}

TEST(BadInputSmooth, RaggedMatrix) {
  ExpectSmoothError(Model(R"({"penalty": "l1"})", R"({"penalty": "l1"})", R"({"penalty": "l1"})",
                          R"("F": [[1, 1], [0]], "H": [[1, 1]])"),
                    "F: row 1 has 1 entries; row 0 has 2");
}

TEST(BadInputSmooth, NonNumericMatrixEntry) {
  ExpectSmoothError(
      Model(R"({"penalty": "l1"})", R"({"penalty": "l1"})", R"({"penalty": "l1"})", R"("F": [["a"]], "H": [[1]])"),
      "F[0][0]: expected a number, got \"a\"");
}

TEST(BadInputSmooth, MatrixEntryBeyondDoubleRange) {
  ExpectSmoothError(
      Model(R"({"penalty": "l1"})", R"({"penalty": "l1"})", R"({"penalty": "l1"})", R"("F": [[1e999]], "H": [[1]])"),
      "model.json: not valid JSON ([json.exception.out_of_range.406] number overflow parsing '1e999')");
}

TEST(BadInputSmooth, NegativeVariance) {
  ExpectSmoothError(Model(R"({"penalty": "quadratic", "covariance": -1})"),
                    "initial: covariance is not positive definite");
}

TEST(BadInputSmooth, CovarianceOfTheWrongSize) {
  ExpectSmoothError(Model(R"({"penalty": "quadratic", "covariance": [[1, 0], [0, 1]]})"),
                    "initial.covariance: is 2x2; need 1x1");
}

TEST(BadInputSmooth, HuberKappaNotPositive) {
  ExpectSmoothError(Model(R"({"penalty": "huber", "kappa": 0})"), "initial: huber kappa = 0; need kappa > 0");
}

TEST(BadInputSmooth, QuantileTauOutsideZeroOne) {
  ExpectSmoothError(Model(R"({"penalty": "l1"})", R"({"penalty": "quantile", "tau": 1.5})"),
                    "process: quantile tau = 1.5; need 0 < tau < 1");
}

TEST(BadInputSmooth, VapnikEpsilonNegative) {
  ExpectSmoothError(Model(R"({"penalty": "l1"})", R"({"penalty": "l1"})", R"({"penalty": "vapnik", "epsilon": -1})"),
                    "measurement: vapnik epsilon = -1; need epsilon >= 0");
}

TEST(BadInputSmooth, UnknownPenalty) {
  ExpectSmoothError(Model(R"({"penalty": "cauchy"})"), "unknown penalty 'cauchy'");
}

TEST(BadInputSmooth, PiecewiseLinearKnotsNotIncreasing) {
  ExpectSmoothError(Model(R"({"penalty": "piecewise_linear", "knots": [1, 0], "values": [0, 0]})"),
                    "piecewise_linear knots must increase strictly");
}

TEST(BadInputSmooth, BoxLowerAboveUpper) {
  ExpectSmoothError(Model(R"({"penalty": "l1"})", R"({"penalty": "box", "lower": [1], "upper": [-1], "M": 1})"),
                    "process: box bound 0: lo = 1, hi = -1; need lo < hi");
}

TEST(BadInputSmooth, WrongNumberOfTimeVaryingPenalties) {
  ExpectSmoothError(Model(R"({"penalty": "l1"})", R"([{"penalty": "l1"}, {"penalty": "l1"}])"),
                    "process: has 2 penalties; need one or T = 3");
}

TEST(BadInputSmooth, NoMeasurementColumn) {
  ExpectCliError(
      "smooth --model " + Quote(Model(R"({"penalty": "l1"})")) + " " + Quote(WriteFile("y.csv", "y\n1\n2\n")),
      "no measurement column (need z, or z1, z2, ...)");
}

TEST(BadInputSmooth, MeasurementsNear1e308) {
  ExpectCliError("smooth --model " + Quote(WriteFile("good_model.json", kGoodModel)) + " " +
                     Quote(WriteFile("z308.csv", "z\n1.7e308\n-1.7e308\n1e308\n")),
                 "z308.csv: the measurements' sum of squares is beyond 1e308 (values near 1e308?); rescale the data");
}

TEST(BadInputSmooth, InfeasibleModel) {
  const std::string box = R"({"penalty": "piecewise_linear", "knots": [-0.1, 0.1], "values": [0, 0]})";
  ExpectSmoothError(Model(box, box, box), "no state sequence keeps every residual inside");
}

TEST(BadInputSmooth, MissingModelOptionIsAUsageError) { ExpectCliError("smooth " + Quote(SmoothData()), "--model", 2); }

// ---- ident logcondens ---------------------------------------------------------------------------------

TEST(BadInputLogcondens, FewerThanTwoDistinctValues) {
  ExpectCliError("logcondens " + Quote(WriteFile("same.csv", "x\n2\n2\n2\n")),
                 "at least 2 distinct sample values, got 1");
}

TEST(BadInputLogcondens, OneSample) {
  ExpectCliError("logcondens " + Quote(WriteFile("one.csv", "x\n2\n")), "at least 2 distinct sample values, got 1");
}

TEST(BadInputLogcondens, UnknownColumn) {
  ExpectCliError("logcondens " + Quote(WriteFile("two.csv", "a,b\n1,5\n2,3\n")) + " --column q", "no column 'q'");
}

TEST(BadInputLogcondens, SeveralColumnsAndNoneNamedX) {
  ExpectCliError("logcondens " + Quote(WriteFile("two.csv", "a,b\n1,5\n2,3\n")),
                 "has 2 columns and none is named 'x'; pass --column NAME");
}

TEST(BadInputLogcondens, ValuesNear1e308) {
  ExpectCliError("logcondens " + Quote(WriteFile("x308.csv", "x\n-1.7e308\n0\n1.7e308\n")),
                 "samples span [-1.7e+308, 1.7e+308], a range beyond the largest double; rescale them");
}

TEST(BadInputLogcondens, UnknownOptionIsAUsageError) {
  ExpectCliError("logcondens " + Quote(WriteFile("ok.csv", "x\n1\n2\n")) + " --bogus", "--bogus", 2);
}

}  // namespace
}  // namespace ident::testing
