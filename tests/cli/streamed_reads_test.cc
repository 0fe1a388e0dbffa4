// The streamed fit of a CSV file (ident/workflow/fit_record.h FitCsvFile with a plan, as `ident fit` runs
// a record of more than 10^6 rows) on a record small enough to fit in memory too: how often it opens the
// file, and that its estimate equals the in-memory fit's (FitTable on the same file read whole).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <limits>
#include <memory>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "cli/command_line.h"
#include "common/error.h"
#include "ident/io/csv.h"
#include "ident/workflow/fit.h"
#include "ident/workflow/fit_record.h"
#include "ident/workflow/internal/fit_steps.h"
#include "ident/workflow/internal/row_count.h"
#include "ident/workflow/internal/shifted_mean_squares.h"
#include "ident/workflow/time_column.h"
#include "tests/support/cli.h"

namespace ident {
namespace {

// A simulated ARX(2,2,1) record with an offset (mean detrending matters), t, u, y at 17 significant digits.
std::string SimulatedRecord(int rows) {
  std::mt19937_64 rng(27);
  std::normal_distribution<double> normal;
  std::string text = "t,u,y\n";
  double y1 = 0, y2 = 0, u1 = 0, u2 = 0;
  for (int k = 0; k < rows; ++k) {
    const double u = 2 + normal(rng);
    const double y = 1.5 * y1 - 0.7 * y2 + u1 + 0.5 * u2 + 0.1 * normal(rng);
    text += fmt::format("{:.17g},{:.17g},{:.17g}\n", 0.01 * k, u, y);
    y2 = y1, y1 = y, u2 = u1, u1 = u;
  }
  return text;
}

workflow::FitRequest Arx221(const std::string& estimator, double split, const char* detrend = "mean") {
  workflow::FitRequest request;
  request.detrend = detrend;
  request.model.output = "y";
  request.model.inputs = {"u"};
  request.model.na = 2;
  request.model.nb = {2};
  request.model.nk = {1};
  request.estimator.estimator = estimator;
  request.split = split;
  return request;
}

struct StreamedFit {
  workflow::FitResult result;
  long opened = 0;  // files opened: the row count, the header and the passes
};

// As `ident fit` streams a record: the row count, the layout (header), the plan, FitCsvFile.
StreamedFit Streamed(const std::string& path, const workflow::FitRequest& request) {
  const long before = io::CsvFilesOpened();
  const long data_lines = workflow::CountCsvDataRows(path);
  std::unique_ptr<workflow::DataSource> source = request.model.MakeSource({"t", "u", "y"}, path);
  workflow::FitOptions length_check;
  length_check.split = request.split;
  const workflow::CsvLayout layout = workflow::CheckCsvLayout(path, {}, *source, length_check, data_lines);
  workflow::FitPlan plan = workflow::PlanFit(request, source->num_parameters(), layout.estimation.count);
  StreamedFit out{workflow::FitCsvFile(path, {}, *source, plan, layout), 0};
  out.opened = io::CsvFilesOpened() - before;
  return out;
}

workflow::FitResult InMemory(const std::string& path, const workflow::FitRequest& request) {
  io::DataTable table = io::ReadCsv(path);
  std::unique_ptr<workflow::DataSource> source = request.model.MakeSource(table.names, path);
  workflow::FitPlan plan =
      workflow::PlanFit(request, source->num_parameters(), workflow::EstimationRows(table.num_rows(), request.split));
  return workflow::FitTable(std::move(table), *source, plan, 0).result;
}

// Opens: the row count, the header, the means pass over the estimation part (which gathers the mean squares
// for the data-scaled prior too; with no detrending there are no means to take, and the prior's mean
// squares take that pass instead), the estimation and scoring pass, and with split = 1 a scoring pass.
TEST(StreamedReads, OpensTheFileOncePerPassAndEqualsTheInMemoryFit) {
  const std::string path = testing::WriteFile("streamed_reads.csv", SimulatedRecord(2'000));
  struct Case {
    const char* estimator;
    double split;
    long opens;
    const char* detrend = "mean";
  };
  for (const Case c : {Case{"rls", 0.5, 4}, Case{"cauchy", 0.5, 4}, Case{"rls", 1.0, 5}, Case{"rls", 0.5, 4, "none"},
                       Case{"cauchy", 0.5, 4, "none"}}) {
    const workflow::FitRequest request = Arx221(c.estimator, c.split, c.detrend);
    const StreamedFit streamed = Streamed(path, request);
    const workflow::FitResult memory = InMemory(path, request);
    EXPECT_EQ(streamed.opened, c.opens) << c.estimator << " split " << c.split << " detrend " << c.detrend;
    ASSERT_EQ(streamed.result.theta.size(), 4);
    EXPECT_EQ(streamed.result.samples_estimation, memory.samples_estimation);
    EXPECT_EQ(streamed.result.updates, memory.updates);
    for (int i = 0; i < 4; ++i) {
      EXPECT_NEAR(streamed.result.theta(i), memory.theta(i), 1e-12 * std::abs(memory.theta(i)))
          << c.estimator << " theta " << i;
      EXPECT_NEAR(streamed.result.theta_std(i), memory.theta_std(i), 1e-12 * memory.theta_std(i));
    }
    EXPECT_NEAR(streamed.result.validation.one_step, memory.validation.one_step, 1e-9);
    // The record's own parameters: the estimate is a real one, not one the two paths share by accident.
    EXPECT_NEAR(streamed.result.theta(0), -1.5, 0.01);
    EXPECT_NEAR(streamed.result.theta(1), 0.7, 0.01);
  }
}

// A file that gains a column between the layout and the passes (as if rewritten while it is fitted) is
// refused with one line naming the row's size, not read with rows of the wrong width.
TEST(StreamedReads, AFileWhoseColumnsChangeBetweenPassesIsRefused) {
  const std::string path = testing::WriteFile("changing_columns.csv", SimulatedRecord(2'000));
  const workflow::FitRequest request = Arx221("rls", 0.5);
  std::unique_ptr<workflow::DataSource> source = request.model.MakeSource({"t", "u", "y"}, path);
  workflow::FitOptions length_check;
  length_check.split = request.split;
  const workflow::CsvLayout layout = workflow::CheckCsvLayout(path, {}, *source, length_check, 2'000);
  workflow::FitPlan plan = workflow::PlanFit(request, source->num_parameters(), layout.estimation.count);
  std::string wider = "t,u,y,x\n";
  const std::string rows = SimulatedRecord(2'000);
  for (std::size_t at = rows.find('\n') + 1; at < rows.size();) {
    const std::size_t end = rows.find('\n', at);
    wider += rows.substr(at, end - at) + ",1\n";
    at = end + 1;
  }
  testing::WriteFile("changing_columns.csv", wider);
  try {
    workflow::FitCsvFile(path, {}, *source, plan, layout);
    ADD_FAILURE() << "a file of 4 columns was fitted with rows of 3";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("row has 3 entries; the file has 4 columns"), std::string::npos) << e.what();
  }
}

// The lines that are neither blank nor comments, less the header, found the plain way: every LF or CR ends a
// line (CRLF: an empty line between).
long PlainDataRows(const std::string& text) {
  long lines = 0;
  std::size_t start = 0;
  while (start <= text.size()) {
    const std::size_t stop = std::min(text.find_first_of("\r\n", start), text.size());
    const std::size_t first = text.find_first_not_of(" \t", start);
    lines += first < stop && text[first] != '#';
    start = stop + 1;
  }
  return std::max(lines - 1, 0L);
}

// The row count of a streamed fit (CountCsvDataRows), which counts a 1 MiB block's lines at once when they
// are all plain data lines, against the plain count: files of 3 MiB whose blocks hold now and then a
// comment, a blank or space-only line, a CR or CRLF line end, or a leading space.
TEST(StreamedReads, RowCountEqualsALineByLineCount) {
  std::mt19937_64 rng(11);
  const std::string kOdd[] = {"# a comment\n", "\n", "  \t\n", "\r", "\r\n", " ", "\t#x\n", "\n\n"};
  for (int file = 0; file < 12; ++file) {
    std::string text = "t,u,y\n";
    std::uniform_int_distribution<int> odd(0, 7), every(0, file < 4 ? 200'000 : 2'000);
    while (text.size() < (3u << 20)) {
      if (every(rng) == 0) text += kOdd[odd(rng)];
      text += fmt::format("{},{:.17g},{}\n", text.size(), 1.0 / static_cast<double>(text.size()), file);
    }
    if (file % 3 == 1) text.pop_back();  // no line end after the last row
    const std::string path = testing::WriteFile("row_count.csv", text);
    EXPECT_EQ(workflow::CountCsvDataRows(path), PlainDataRows(text)) << "file " << file;
  }
}

// A regular file of 2 MiB or more is counted in two halves at once, cut just after the first LF at or past its
// middle (here from 4 KiB on: internal::CountCsvDataRows). Files whose middle falls, as a closing comment's length
// moves it byte by byte, on and next to a CRLF, an empty line, a comment, a CR-only line end and a line without a
// line end before the next; a file with CR-only line ends throughout (no LF to cut at: one thread); and one
// 2 MiB file at the default threshold. Each against the plain count.
TEST(StreamedReads, RowCountOfAFileCutInTwoEqualsALineByLineCount) {
  constexpr long kSmall = 4 << 10;
  std::string rows;
  for (int k = 0; rows.size() < 3u << 10; ++k) rows += fmt::format("{},{:.17g},1\n", k, 1.0 / (k + 1));
  for (const std::string odd : {"\r\n", "\n\n", "# a comment\n", "7,8\r9,10", " \t\n#\r"}) {
    // The middle is (pad − 8)/2 bytes past the odd text's start: from 1 before it to 1 past its end.
    const std::string lead = "#" + std::string(odd.size() + 2, 'x') + "\nt,u,y\n";
    for (int pad = 6; pad <= 2 * static_cast<int>(odd.size()) + 10; pad += 2) {
      const std::string text = lead + rows + odd + rows + "#" + std::string(pad, 'x') + "\n";
      const std::string path = testing::WriteFile("row_count_cut.csv", text);
      EXPECT_EQ(workflow::internal::CountCsvDataRows(path, kSmall), PlainDataRows(text))
          << "odd " << odd.size() << " pad " << pad;
    }
  }
  std::string cr_only = "t,u,y\r";
  for (int k = 0; cr_only.size() < 8u << 10; ++k) cr_only += fmt::format("{},{},1\r", k, k % 7);
  EXPECT_EQ(workflow::internal::CountCsvDataRows(testing::WriteFile("row_count_cr.csv", cr_only), kSmall),
            PlainDataRows(cr_only));
  std::string large = "t,u,y\n";
  for (int k = 0; large.size() < (2u << 20) + 100; ++k)
    large += fmt::format("{},{},1\n{}", k, k % 7, k % 97 ? "" : "#\n");
  EXPECT_EQ(workflow::CountCsvDataRows(testing::WriteFile("row_count_large.csv", large)), PlainDataRows(large));
}

// The data-scaled prior's mean squares gathered in the means pass about a provisional centre
// (internal::ShiftedMeanSquares) against internal::MeanSquares over the rows detrended by their means: ARX and
// a static regression with an intercept, with missing samples, an offset of 1e3, the first rows far from
// the mean (a poor centre), and fewer rows than the centre takes.
TEST(StreamedReads, MeanSquaresOfTheMeansPassEqualThoseOfTheirOwnPass) {
  std::mt19937_64 rng(3);
  std::normal_distribution<double> normal;
  const std::vector<std::string> columns = {"t", "u", "x", "y"};
  workflow::ModelSpec arx;
  arx.output = "y";
  arx.inputs = {"u"};
  arx.nb = {3};
  arx.nk = {2};
  workflow::ModelSpec regression;
  regression.output = "y";
  regression.regressors = {"u", "x"};
  regression.intercept = true;
  for (const int rows : {300, 5'000}) {
    for (const double early : {0.0, 50.0}) {  // the first rows' shift, in standard deviations of u and y
      Eigen::MatrixXd table(rows, 4);
      for (int r = 0; r < rows; ++r) {
        const double shift = r < 700 ? early : 0.0;
        table.row(r) << 0.01 * r, 1e3 + shift + normal(rng), -2 + 0.1 * normal(rng), 1e3 + 2 * shift + normal(rng);
      }
      table(17, 1) = table(200, 3) = std::numeric_limits<double>::quiet_NaN();
      Eigen::VectorXd offset = Eigen::VectorXd::Zero(4);
      for (int c = 1; c < 4; ++c) {
        const Eigen::VectorXd column = table.col(c);
        offset(c) = column.array().isNaN().select(0.0, column.array()).sum() / column.array().isFinite().count();
      }
      for (const workflow::ModelSpec* model : {&arx, &regression}) {
        SCOPED_TRACE(fmt::format("{} rows, early shift {}, {}", rows, early, model == &arx ? "ARX" : "static"));
        std::unique_ptr<workflow::DataSource> source = model->MakeSource(columns, "table");
        ASSERT_TRUE(source->affine_in_rows());
        workflow::internal::MeanSquares direct(*source);
        for (int r = 0; r < rows; ++r) direct.Add(Eigen::VectorXd(table.row(r).transpose() - offset));
        const Eigen::VectorXd want = direct.Get();
        workflow::internal::ShiftedMeanSquares shifted(*source, 4);
        for (int r = 0; r < rows; ++r) shifted.Add(table.row(r).transpose());
        const Eigen::VectorXd got = shifted.Get(offset);
        ASSERT_EQ(got.size(), want.size());
        for (Eigen::Index i = 0; i < want.size(); ++i) {
          EXPECT_NEAR(got(i), want(i), 1e-11 * want(i)) << "entry " << i;
          EXPECT_GT(want(i), 0.005) << "entry " << i;  // a spread, not a cancellation to 0
        }
      }
    }
  }
}

using testing::ProcessBytesRead;

// `ident fit FILE` with ARX(2,2,1) and `extra` options, run in-process: exit code, stdout, and the files opened
// (io::CsvFilesOpened) and bytes read (ProcessBytesRead) while it ran.
struct InProcessFit {
  int code = -1;
  std::string out;
  long opened = 0, bytes_read = 0;
};
InProcessFit FitInProcess(const std::string& path, std::vector<std::string> extra) {
  std::vector<std::string> words = {"ident", "fit", path,   "--output", "y",    "--input", "u",
                                    "--na",  "2",   "--nb", "2",        "--nk", "1"};
  words.insert(words.end(), extra.begin(), extra.end());
  std::vector<char*> argv;
  for (std::string& w : words) argv.push_back(w.data());
  InProcessFit fit;
  const long opened = io::CsvFilesOpened(), read = ProcessBytesRead();
  ::testing::internal::CaptureStdout();
  fit.code = cli::RunCommandLine(static_cast<int>(argv.size()), argv.data());
  fit.bytes_read = ProcessBytesRead() - read;  // before the captured output is read back
  fit.opened = io::CsvFilesOpened() - opened;
  fit.out = ::testing::internal::GetCapturedStdout();
  return fit;
}

// `ident fit` on a regular file too small to hold more rows than are read whole (two bytes per row at
// least) reads it once, into memory: no row count, no separate look at the header.
TEST(InMemoryReads, ASmallFileIsOpenedOnce) {
  const std::string path = testing::WriteFile("in_memory_reads.csv", SimulatedRecord(2'000));
  const InProcessFit fit = FitInProcess(path, {"--json"});
  EXPECT_EQ(fit.code, 0);
  EXPECT_NE(fit.out.find("\"theta\""), std::string::npos);
  EXPECT_EQ(fit.opened, 1);
}

// `ident fit` on a regular file of fewer rows than are read whole, but too large to tell so from its size alone
// (more than two bytes per row), reads it whole at once: about one file size, where counting its rows first and
// then reading it take two; with --save too, whose checksum is taken from the bytes as they are read.
TEST(InMemoryReads, AFileThatFitsIsReadOnce) {
  if (ProcessBytesRead() < 0) GTEST_SKIP() << "no /proc/self/io (a kernel without I/O accounting): bytes read unknown";
  const std::string text = SimulatedRecord(60'000);
  ASSERT_GT(text.size(), 3'000'000u);
  const std::string path = testing::WriteFile("in_memory_read_once.csv", text);
  const double size = static_cast<double>(text.size());
  const InProcessFit fit = FitInProcess(path, {"--json"});
  EXPECT_EQ(fit.code, 0);
  EXPECT_NE(fit.out.find("\"residual_analysis\": {"), std::string::npos) << "read whole: with the residual analysis";
  EXPECT_GE(static_cast<double>(fit.bytes_read), size);
  EXPECT_LT(static_cast<double>(fit.bytes_read), 1.2 * size) << fit.bytes_read << " bytes read";
  const std::string model = testing::TempDir() + "/read_once_model.json";
  const InProcessFit saved = FitInProcess(path, {"--save", model});
  EXPECT_EQ(saved.code, 0);
  EXPECT_LT(static_cast<double>(saved.bytes_read), 1.2 * size) << saved.bytes_read << " bytes read with --save";
  // FNV-1a, 64 bits, of the file's bytes, here.
  std::uint64_t h = 14695981039346656037ull;
  for (const char c : text) h = (h ^ static_cast<unsigned char>(c)) * 1099511628211ull;
  const std::string saved_model = testing::ReadFile(model);
  EXPECT_NE(saved_model.find(fmt::format("\"fnv1a64\": \"{:016x}\"", h)), std::string::npos) << saved_model;
}

// The record of SimulatedRecord without the rows in [first, last) of each pair: gaps in its time column.
std::string WithoutRows(const std::string& text, const std::vector<std::pair<int, int>>& dropped) {
  std::string out;
  std::size_t at = 0;
  for (int line = 0; at < text.size(); ++line) {
    const std::size_t end = text.find('\n', at) + 1;
    const int row = line - 1;  // data row, 0-based (line 0 is the header)
    bool keep = true;
    for (const auto& [first, last] : dropped) keep = keep && !(row >= first && row < last);
    if (keep) out += text.substr(at, end - at);
    at = end;
  }
  return out;
}

// The streamed fit checks the time column in its estimation pass (the gaps of an in-memory check), and with
// --missing fills each gap's rows before the row that ends it, to the same estimate as the in-memory fit of
// the filled table.
TEST(StreamedReads, TheTimeColumnIsCheckedAndItsGapsFilledAsInMemory) {
  const std::string path =
      testing::WriteFile("streamed_gaps.csv", WithoutRows(SimulatedRecord(2'000), {{500, 510}, {1'500, 1'503}}));
  const workflow::FitRequest request = Arx221("cauchy", 0.5);
  for (bool fill : {false, true}) {
    SCOPED_TRACE(fill ? "filled" : "reported");
    const io::CsvOptions csv{.missing_as_nan = fill};
    // In memory, as `ident fit` checks and fills a table.
    io::DataTable table = io::ReadCsv(path, csv);
    std::unique_ptr<workflow::DataSource> memory_source = request.model.MakeSource(table.names, path);
    const std::optional<workflow::TimeCheck> memory_time =
        workflow::CheckRecordTime(table, memory_source->used_columns(), fill);
    ASSERT_TRUE(memory_time.has_value());
    ASSERT_EQ(memory_time->gaps.size(), 2u);
    workflow::FitPlan memory_plan = workflow::PlanFit(request, memory_source->num_parameters(),
                                                      workflow::EstimationRows(table.num_rows(), request.split));
    const workflow::FitResult memory = workflow::FitTable(std::move(table), *memory_source, memory_plan, 0).result;
    // Streamed.
    std::unique_ptr<workflow::DataSource> source = request.model.MakeSource({"t", "u", "y"}, path);
    std::optional<workflow::TimeCheck> time;
    if (fill) time = workflow::ScanCsvTime(path, csv, source->used_columns());
    workflow::FitOptions length_check;
    length_check.split = request.split;
    const workflow::CsvLayout layout =
        workflow::CheckCsvLayout(path, csv, *source, length_check, -1, time ? &*time : nullptr);
    workflow::FitPlan plan = workflow::PlanFit(request, source->num_parameters(), layout.estimation.count);
    const workflow::FitResult streamed =
        workflow::FitCsvFile(path, csv, *source, plan, layout, time ? &*time : nullptr);

    ASSERT_TRUE(streamed.time.has_value());
    EXPECT_EQ(streamed.time->column, "t");
    ASSERT_EQ(streamed.time->gaps.size(), 2u);
    const long missing[] = {10, 3};
    const int rows[] = {501, 1'491};  // the data row that ends each gap
    for (int g = 0; g < 2; ++g) {
      const workflow::TimeGap& s = streamed.time->gaps[static_cast<std::size_t>(g)];
      const workflow::TimeGap& m = memory_time->gaps[static_cast<std::size_t>(g)];
      EXPECT_EQ(s.row, rows[g]);
      EXPECT_EQ(s.row, m.row);
      EXPECT_EQ(s.t_before, m.t_before);
      EXPECT_EQ(s.t_after, m.t_after);
      EXPECT_EQ(s.missing, missing[g]);
      EXPECT_EQ(s.missing, m.missing);
      EXPECT_EQ(s.filled, fill ? missing[g] : 0);
      EXPECT_EQ(s.filled, m.filled);
    }
    EXPECT_NEAR(streamed.time->median_step, 0.01, 1e-12);
    EXPECT_EQ(streamed.samples_estimation, memory.samples_estimation);
    EXPECT_EQ(streamed.updates, memory.updates);
    EXPECT_EQ(streamed.rejected, memory.rejected);
    ASSERT_EQ(streamed.theta.size(), 4);
    for (int i = 0; i < 4; ++i) EXPECT_NEAR(streamed.theta(i), memory.theta(i), 1e-12 * std::abs(memory.theta(i)));
    EXPECT_NEAR(streamed.validation.one_step, memory.validation.one_step, 1e-9);
  }
  // Filled, the record is 13 rows longer.
  const io::CsvOptions missing{.missing_as_nan = true};
  std::unique_ptr<workflow::DataSource> source = request.model.MakeSource({"t", "u", "y"}, path);
  std::optional<workflow::TimeCheck> time = workflow::ScanCsvTime(path, missing, source->used_columns());
  ASSERT_TRUE(time.has_value());
  EXPECT_EQ(workflow::CheckCsvLayout(path, missing, *source, {}, -1, &*time).rows, 2'000);
  EXPECT_EQ(workflow::CheckCsvLayout(path, missing, *source, {}, -1, nullptr).rows, 1'987);
}

// A time that does not increase stops the streamed fit with the in-memory check's message.
TEST(StreamedReads, ATimeThatDoesNotIncreaseIsAnError) {
  std::string text = SimulatedRecord(3'000);
  const std::size_t at = text.find("\n20,");  // the data row of t = 20 (line 2 002) gets t = 19
  ASSERT_NE(at, std::string::npos);
  text.replace(at + 1, 2, "19");
  const std::string path = testing::WriteFile("streamed_back.csv", text);
  const workflow::FitRequest request = Arx221("rls", 0.5);
  std::unique_ptr<workflow::DataSource> source = request.model.MakeSource({"t", "u", "y"}, path);
  workflow::FitOptions length_check;
  length_check.split = request.split;
  const workflow::CsvLayout layout = workflow::CheckCsvLayout(path, {}, *source, length_check);
  workflow::FitPlan plan = workflow::PlanFit(request, source->num_parameters(), layout.estimation.count);
  const std::string expected = path + ":2002: time column 't' does not increase: 19 after 19.990000000000002";
  try {
    workflow::FitCsvFile(path, {}, *source, plan, layout);
    ADD_FAILURE() << "no error";
  } catch (const DataError& e) {
    EXPECT_EQ(std::string(e.what()), expected);
  }
  try {
    workflow::ScanCsvTime(path, {}, source->used_columns());
    ADD_FAILURE() << "no error";
  } catch (const DataError& e) {
    EXPECT_EQ(std::string(e.what()), expected);
  }
}

// The median of the last steps as rows arrive equals the median of that window sorted afresh.
TEST(ArrivingTimeCheck, ItsMedianIsThatOfTheLastRegularSteps) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> step(0.9, 1.1);
  workflow::ArrivingTimeCheck check;
  std::vector<double> steps;
  double t = 0;
  for (int k = 0; k < 500; ++k) {
    const double s = step(rng);
    t += s;
    ASSERT_FALSE(check.Next(t, k + 1, "t", "test").has_value());
    if (k == 0) continue;  // the first row has no step
    steps.push_back(s);
    const std::size_t n = std::min<std::size_t>(steps.size(), workflow::ArrivingTimeCheck::kSteps);
    std::vector<double> window(steps.end() - static_cast<std::ptrdiff_t>(n), steps.end());
    std::sort(window.begin(), window.end());
    const double median = n % 2 ? window[n / 2] : (window[n / 2 - 1] + window[n / 2]) / 2;
    EXPECT_NEAR(check.median_step(), median, 1e-12) << k;
  }
}

// Jittered and repeated steps with gaps among them: each row is a gap exactly when its step exceeds
// kTimeGapFactor times the median of the last kSteps regular steps (sorted here, by brute force), and the
// gap's step is that median.
TEST(ArrivingTimeCheck, FindsTheGapsThatTheMedianOfTheLastRegularStepsDefines) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> jitter(0.5, 1.4), unit(0, 1);
  const double repeated[] = {0.75, 1.0, 1.25};
  workflow::ArrivingTimeCheck check;
  std::vector<double> regular;
  double t = 0;
  int gaps = 0;
  ASSERT_FALSE(check.Next(t, 1, "t", "test").has_value());
  for (int k = 2; k < 20'000; ++k) {
    const double u = unit(rng);
    const double before = t;
    t += u < 0.02 ? 3 + 5 * unit(rng) : u < 0.5 ? repeated[k % 3] : jitter(rng);
    const double s = t - before;  // the step as the check sees it
    const std::optional<workflow::TimeGap> gap = check.Next(t, k, "t", "test");
    const std::size_t n = std::min<std::size_t>(regular.size(), workflow::ArrivingTimeCheck::kSteps);
    std::vector<double> window(regular.end() - static_cast<std::ptrdiff_t>(n), regular.end());
    std::sort(window.begin(), window.end());
    const double median = n == 0 ? 0 : n % 2 ? window[n / 2] : (window[n / 2 - 1] + window[n / 2]) / 2;
    const bool close_call = n > 0 && std::abs(s - workflow::kTimeGapFactor * median) <= 1e-9;
    if (!close_call) {
      ASSERT_EQ(gap.has_value(), n > 0 && s > workflow::kTimeGapFactor * median)
          << "row " << k << ", step " << s << ", median " << median;
    }
    if (gap) {
      ++gaps;
      EXPECT_NEAR(gap->step, median, 1e-12) << k;
    } else {
      regular.push_back(s);
    }
  }
  EXPECT_GT(gaps, 100);
  std::vector<double> last(regular.end() - workflow::ArrivingTimeCheck::kSteps, regular.end());
  std::sort(last.begin(), last.end());
  EXPECT_EQ(check.median_step(), last[workflow::ArrivingTimeCheck::kSteps / 2]);
}

}  // namespace
}  // namespace ident
