// The streamed fit of a CSV file (ident/workflow/fit_record.h FitCsvFile with a plan, as `ident fit` runs
// a record of more than 10^6 rows) on a record small enough to fit in memory too: how often it opens the
// file, and that its estimate equals the in-memory fit's (FitTable on the same file read whole).
#include <cmath>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "cli/command_line.h"
#include "ident/io/csv.h"
#include "ident/workflow/fit.h"
#include "ident/workflow/fit_record.h"
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

workflow::FitRequest Arx221(const std::string& estimator, double split) {
  workflow::FitRequest request;
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

// Opens: the row count, the header, the means pass over the estimation part, the mean squares pass for
// RLS's data-scaled prior (RLS only), the estimation and scoring pass, and with split = 1 a scoring pass.
TEST(StreamedReads, OpensTheFileOncePerPassAndEqualsTheInMemoryFit) {
  const std::string path = testing::WriteFile("streamed_reads.csv", SimulatedRecord(20'000));
  struct Case {
    const char* estimator;
    double split;
    long opens;
  };
  for (const Case c : {Case{"rls", 0.5, 5}, Case{"cauchy", 0.5, 4}, Case{"rls", 1.0, 6}}) {
    const workflow::FitRequest request = Arx221(c.estimator, c.split);
    const StreamedFit streamed = Streamed(path, request);
    const workflow::FitResult memory = InMemory(path, request);
    EXPECT_EQ(streamed.opened, c.opens) << c.estimator << " split " << c.split;
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

// `ident fit` on a regular file too small to hold more rows than are read whole (two bytes per row at
// least) reads it once, into memory: no row count, no separate look at the header.
TEST(InMemoryReads, ASmallFileIsOpenedOnce) {
  const std::string path = testing::WriteFile("in_memory_reads.csv", SimulatedRecord(2'000));
  std::vector<std::string> words = {"ident", "fit",  path, "--output", "y", "--input", "u",
                                    "--na",  "2",    "--nb", "2",      "--nk", "1",     "--json"};
  std::vector<char*> argv;
  for (std::string& w : words) argv.push_back(w.data());
  const long before = io::CsvFilesOpened();
  ::testing::internal::CaptureStdout();
  const int code = cli::RunCommandLine(static_cast<int>(argv.size()), argv.data());
  const std::string out = ::testing::internal::GetCapturedStdout();
  EXPECT_EQ(code, 0);
  EXPECT_NE(out.find("\"theta\""), std::string::npos);
  EXPECT_EQ(io::CsvFilesOpened() - before, 1);
}

}  // namespace
}  // namespace ident
