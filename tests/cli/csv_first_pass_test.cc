// The first pass of a streamed fit in one read of the file (workflow::ScanCsvFirstPass): its layout, its
// detrending offsets and the fit that uses them against the two passes it replaces (CountCsvDataRows with
// CheckCsvLayout, then FitCsvFile's own means pass), bit for bit, on records whose lines keep their length or
// grow or shrink along the file (the guess of where the estimation part ends is then short or long), with and
// without a header; a bad row in the part read twice; the files it leaves to the two passes; and the bytes read.
#include <cmath>
#include <memory>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "common/error.h"
#include "ident/io/csv.h"
#include "ident/workflow/fit.h"
#include "ident/workflow/fit_record.h"
#include "ident/workflow/internal/first_pass.h"
#include "tests/support/cli.h"

namespace ident {
namespace {

// Significant digits of y in the rows before and after the middle of a record: lines that keep their length
// (17, 17), grow along the file (6, 17) or shrink (17, 6).
struct LineDigits {
  int early = 17, late = 17;
};

// y(t) = 1.5 y(t−1) − 0.7 y(t−2) + u(t−1) + 0.5 u(t−2) + 0.1 e(t) with u = 2 + N(0, 1) (an offset: the means
// matter), as t,u,y; the header "t,u,y" or none (the columns are then c1, c2, c3).
std::string DriftRecord(int rows, LineDigits digits, bool header = true) {
  std::mt19937_64 rng(41);
  std::normal_distribution<double> normal;
  std::string text = header ? "t,u,y\n" : "";
  double y1 = 0, y2 = 0, u1 = 0, u2 = 0;
  for (int k = 0; k < rows; ++k) {
    const double u = 2 + normal(rng);
    const double y = 1.5 * y1 - 0.7 * y2 + u1 + 0.5 * u2 + 0.1 * normal(rng);
    text += fmt::format("{},{:.17g},{:.{}g}\n", k, u, y, k < rows / 2 ? digits.early : digits.late);
    y2 = y1, y1 = y, u2 = u1, u1 = u;
  }
  return text;
}

// ARX(2,2,1) of y (c3 without a header) on u (c2) by `estimator`, the first `split` of the rows estimating.
workflow::FitRequest FirstPassRequest(const std::string& estimator, double split, bool header = true) {
  workflow::FitRequest request;
  request.estimator.estimator = estimator;
  request.split = split;
  workflow::ModelSpec& arx = request.model;
  arx.output = header ? "y" : "c3";
  arx.inputs = {header ? "u" : "c2"};
  arx.na = 2, arx.nb = {2}, arx.nk = {1};
  return request;
}

std::vector<std::string> ColumnNames(bool header) {
  return header ? std::vector<std::string>{"t", "u", "y"} : std::vector<std::string>{"c1", "c2", "c3"};
}

// The margin of the guess in rows is at least 100 here (4 096 by default), so that records of a few thousand
// rows have a tail to count.
workflow::internal::FirstPassLimits SmallGuessMargin(long held_values = 1L << 18) {
  workflow::internal::FirstPassLimits limits;
  limits.min_margin_rows = 100;
  limits.held_values = held_values;
  return limits;
}

std::optional<workflow::CsvFirstPass> RunFirstPass(const std::string& path, const workflow::FitRequest& request,
                                                   const workflow::internal::FirstPassLimits& limits,
                                                   bool header = true) {
  std::unique_ptr<workflow::DataSource> source = request.model.MakeSource(ColumnNames(header), path);
  const workflow::FitPlan planned = workflow::PlanFitOptions(request, source->num_parameters());
  return workflow::internal::ScanCsvFirstPass(path, {}, *source, planned.options,
                                              planned.scaled_prior && source->affine_in_rows(), limits);
}

// The streamed fit with the first pass, and with the row count and the means pass it replaces.
struct BothFits {
  workflow::CsvFirstPass first;
  workflow::CsvLayout counted;
  workflow::FitResult one_read, two_passes;
};
BothFits BothStreamedFits(const std::string& path, const workflow::FitRequest& request,
                          const workflow::internal::FirstPassLimits& limits, bool header = true) {
  BothFits fits;
  const std::optional<workflow::CsvFirstPass> first = RunFirstPass(path, request, limits, header);
  if (!first) throw std::runtime_error("no first pass for " + path);
  fits.first = *first;
  std::unique_ptr<workflow::DataSource> source = request.model.MakeSource(ColumnNames(header), path);
  workflow::FitPlan plan = workflow::PlanFit(request, source->num_parameters(), first->layout.estimation.count);
  fits.one_read = workflow::FitCsvFile(path, {}, *source, plan, *first);
  workflow::FitOptions length_check;
  length_check.split = request.split;
  fits.counted = workflow::CheckCsvLayout(path, {}, *source, length_check, workflow::CountCsvDataRows(path), nullptr);
  workflow::FitPlan again = workflow::PlanFit(request, source->num_parameters(), fits.counted.estimation.count);
  fits.two_passes = workflow::FitCsvFile(path, {}, *source, again, fits.counted);
  return fits;
}

void ExpectTheSameStreamedFit(const BothFits& f) {
  EXPECT_EQ(f.first.layout.rows, f.counted.rows);
  EXPECT_EQ(f.first.layout.columns, f.counted.columns);
  EXPECT_EQ(f.first.layout.estimation.first, f.counted.estimation.first);
  EXPECT_EQ(f.first.layout.estimation.count, f.counted.estimation.count);
  EXPECT_EQ(f.first.layout.validation.first, f.counted.validation.first);
  EXPECT_EQ(f.first.layout.validation.count, f.counted.validation.count);
  ASSERT_EQ(f.one_read.theta.size(), 4);
  ASSERT_EQ(f.two_passes.theta.size(), 4);
  for (int i = 0; i < 4; ++i) {  // the same offsets, so the same numbers, bit for bit
    EXPECT_EQ(f.one_read.theta(i), f.two_passes.theta(i)) << "theta " << i;
    EXPECT_EQ(f.one_read.theta_std(i), f.two_passes.theta_std(i)) << "theta_std " << i;
  }
  EXPECT_EQ(f.one_read.validation.one_step, f.two_passes.validation.one_step);
  EXPECT_EQ(f.one_read.updates, f.two_passes.updates);
  // The record's own parameters: a real estimate, not one the two paths share by accident.
  EXPECT_NEAR(f.one_read.theta(0), -1.5, 0.02);
  EXPECT_NEAR(f.one_read.theta(1), 0.7, 0.02);
}

TEST(StreamedFirstPass, LayoutAndFitEqualThoseOfTheCountAndTheMeansPass) {
  const std::string path = testing::WriteFile("first_pass.csv", DriftRecord(2'000, {}));
  struct Case {
    const char* estimator;  // rls: the mean squares come along; cauchy: a robust offset
    double split;
  };
  for (const Case c : {Case{"rls", 0.3}, Case{"rls", 0.5}, Case{"rls", 1.0}, Case{"cauchy", 0.5}}) {
    SCOPED_TRACE(fmt::format("{}, split {}", c.estimator, c.split));
    const BothFits fits = BothStreamedFits(path, FirstPassRequest(c.estimator, c.split), SmallGuessMargin());
    EXPECT_FALSE(fits.first.means_pass);
    EXPECT_EQ(fits.first.data_lines, 2'000);
    ExpectTheSameStreamedFit(fits);
  }
}

// A guess past the estimation part's end (here 3 % of the rows past it, on lines that grow along the file): the
// head's last rows are held until the count is complete, or, beyond the limit of values held, the means pass is
// made after all. Lines that shrink along the file, with the default margin before the guess: the estimation
// part's rows past the head are read again from there.
TEST(StreamedFirstPass, AGuessPastOrBeforeTheEstimationPartsEnd) {
  struct Case {
    LineDigits digits;
    double margin_fraction;
    long held_values;
    bool means_pass;
  };
  for (const Case c :
       {Case{{6, 17}, -0.03, 1L << 18, false}, Case{{6, 17}, -0.03, 30, true}, Case{{17, 6}, 0.002, 1L << 18, false}}) {
    const std::string path = testing::WriteFile("first_pass_drift.csv", DriftRecord(2'000, c.digits));
    workflow::internal::FirstPassLimits limits = SmallGuessMargin(c.held_values);
    limits.margin_fraction = c.margin_fraction;
    SCOPED_TRACE(fmt::format("digits {} then {}, margin {} of the rows, {} values held at most", c.digits.early,
                             c.digits.late, c.margin_fraction, c.held_values));
    const BothFits fits = BothStreamedFits(path, FirstPassRequest("rls", 0.5), limits);
    EXPECT_EQ(fits.first.means_pass, c.means_pass);
    ExpectTheSameStreamedFit(fits);
  }
}

// The offsets at splits a few rows apart, with the rows held (a guess 3 % of the rows past the estimation part's
// end) ending on either side of it, against the means of the estimation part of the file read whole, formed as
// the means pass forms them (m ← m + (v − m)/k): equal bit for bit.
TEST(StreamedFirstPass, OffsetsAreTheEstimationPartsMeansAtEverySplit) {
  const std::string path = testing::WriteFile("first_pass_splits.csv", DriftRecord(2'000, {6, 17}));
  const io::DataTable table = io::ReadCsv(path);
  for (double split = 0.45; split < 0.55; split += 0.0013) {
    SCOPED_TRACE(fmt::format("split {}", split));
    workflow::internal::FirstPassLimits past;
    past.margin_fraction = -0.03;
    const std::optional<workflow::CsvFirstPass> first = RunFirstPass(path, FirstPassRequest("rls", split), past);
    ASSERT_TRUE(first.has_value());
    const long estimation = static_cast<long>(std::floor(split * 2'000));
    ASSERT_EQ(first->layout.estimation.count, estimation);
    ASSERT_EQ(first->offset.size(), 3);
    EXPECT_EQ(first->offset(0), 0.0);  // t: not used by the model
    for (int c = 1; c < 3; ++c) {
      double mean = 0;
      for (long k = 0; k < estimation; ++k) mean += (table.values(k, c) - mean) / static_cast<double>(k + 1);
      EXPECT_EQ(first->offset(c), mean) << "column " << c;
    }
  }
}

// Rows of 28 bytes each under a header of 6 ("t,u,y"), and no margin: the head ends a row before, at or a row
// past the estimation part's end as N and the split vary, so that the last row of the head is sometimes the
// first one past it — certainly outside only once the count is complete.
TEST(StreamedFirstPass, OffsetsWhereTheHeadEndsNextToTheEstimationPart) {
  workflow::internal::FirstPassLimits no_margin;
  no_margin.min_margin_rows = 0;
  no_margin.margin_fraction = 0;
  for (int rows = 2'001; rows <= 2'006; ++rows) {
    std::string text = "t,u,y\n";
    std::mt19937_64 rng(rows);
    std::normal_distribution<double> normal;
    for (int k = 0; k < rows; ++k) text += fmt::format("{:07d},{:+09.5f},{:+09.5f}\n", k, normal(rng), normal(rng));
    const std::string path = testing::WriteFile("first_pass_fixed.csv", text);
    const io::DataTable table = io::ReadCsv(path);
    for (const double split : {0.3, 0.5, 0.7}) {
      SCOPED_TRACE(fmt::format("{} rows, split {}", rows, split));
      const std::optional<workflow::CsvFirstPass> first = RunFirstPass(path, FirstPassRequest("rls", split), no_margin);
      ASSERT_TRUE(first.has_value());
      const long estimation = static_cast<long>(std::floor(split * rows));
      ASSERT_EQ(first->layout.estimation.count, estimation);
      for (int c = 1; c < 3; ++c) {
        double mean = 0;
        for (long k = 0; k < estimation; ++k) mean += (table.values(k, c) - mean) / static_cast<double>(k + 1);
        EXPECT_EQ(first->offset(c), mean) << "column " << c;
      }
    }
  }
}

// Without a header the file's first line is a row: the rows read again after the head are read under it, and
// it is not taken twice.
TEST(StreamedFirstPass, AFileWithoutAHeader) {
  const std::string path = testing::WriteFile("first_pass_no_header.csv", DriftRecord(2'000, {17, 6}, false));
  for (const double split : {0.5, 0.7}) {
    SCOPED_TRACE(fmt::format("split {}", split));
    const BothFits fits = BothStreamedFits(path, FirstPassRequest("rls", split, false), SmallGuessMargin(), false);
    EXPECT_FALSE(fits.first.means_pass);
    EXPECT_EQ(fits.first.data_lines, 1'999);  // as CountCsvDataRows counts: the first line taken for a header
    EXPECT_EQ(fits.first.layout.rows, 2'000);
    ExpectTheSameStreamedFit(fits);
  }
}

// A bad cell in the last row of the estimation part, which the head does not reach when the lines shrink along
// the file: reported at its line, as reading the file whole reports it.
TEST(StreamedFirstPass, ABadRowPastTheHeadIsReportedAtItsLine) {
  std::string text = DriftRecord(2'000, {17, 6});
  std::size_t at = 0;
  for (int line = 1; line < 1'001; ++line) at = text.find('\n', at) + 1;  // line 1 001: row 1 000 of 2 000
  text.insert(text.find(',', at) + 1, "x");
  const std::string path = testing::WriteFile("first_pass_bad.csv", text);
  std::string want;
  try {
    io::ReadCsv(path);
  } catch (const DataError& e) {
    want = e.what();
  }
  ASSERT_NE(want.find(":1001:"), std::string::npos) << want;
  try {
    RunFirstPass(path, FirstPassRequest("rls", 0.5), SmallGuessMargin());
    ADD_FAILURE() << "a bad cell in the estimation part was not reported";
  } catch (const DataError& e) {
    EXPECT_EQ(std::string(e.what()), want);
  }
}

// Where the first pass does not apply the caller counts and reads as before: no detrending (no means to take),
// a comment in the file's first 64 KiB, a split outside (0, 1] (reported by the layout's check).
TEST(StreamedFirstPass, LeavesToTheTwoPassesWhatItDoesNotTake) {
  const std::string plain = DriftRecord(2'000, {});
  const std::string path = testing::WriteFile("first_pass_plain.csv", plain);
  workflow::FitRequest none = FirstPassRequest("rls", 0.5);
  none.detrend = "none";
  EXPECT_FALSE(RunFirstPass(path, none, SmallGuessMargin()).has_value());
  EXPECT_FALSE(RunFirstPass(path, FirstPassRequest("rls", 1.5), SmallGuessMargin()).has_value());
  const std::string commented = testing::WriteFile("first_pass_comment.csv", "# a comment\n" + plain);
  EXPECT_FALSE(RunFirstPass(commented, FirstPassRequest("rls", 0.5), SmallGuessMargin()).has_value());
  EXPECT_TRUE(RunFirstPass(path, FirstPassRequest("rls", 0.5), SmallGuessMargin()).has_value());
}

// The first pass reads the file once and the whole streamed fit twice, besides a few fixed blocks (a look at the
// file's start and at the guessed line start, a header each reader takes, the rows read again after the head):
// at most 2 MiB here. The count and the means pass it replaces read the estimation part twice.
TEST(StreamedFirstPass, TheStreamedFitReadsTheFileTwice) {
  if (testing::ProcessBytesRead() < 0) GTEST_SKIP() << "no /proc/self/io (a kernel without I/O accounting)";
  const std::string text = DriftRecord(50'000, {});
  const std::string path = testing::WriteFile("first_pass_bytes.csv", text);
  const double size = static_cast<double>(text.size());
  const workflow::FitRequest request = FirstPassRequest("rls", 0.5);
  std::unique_ptr<workflow::DataSource> source = request.model.MakeSource(ColumnNames(true), path);
  const workflow::FitPlan planned = workflow::PlanFitOptions(request, source->num_parameters());
  long before = testing::ProcessBytesRead();
  const std::optional<workflow::CsvFirstPass> first =
      workflow::ScanCsvFirstPass(path, {}, *source, planned.options, source->affine_in_rows());
  const double first_pass = static_cast<double>(testing::ProcessBytesRead() - before);
  ASSERT_TRUE(first.has_value());
  EXPECT_FALSE(first->means_pass);
  workflow::FitPlan plan = workflow::PlanFit(request, source->num_parameters(), first->layout.estimation.count);
  before = testing::ProcessBytesRead();
  workflow::FitCsvFile(path, {}, *source, plan, *first);
  const double fit = static_cast<double>(testing::ProcessBytesRead() - before);
  EXPECT_LE(first_pass, size + (1 << 20)) << "the file is " << size << " bytes";
  EXPECT_LE(first_pass + fit, 2 * size + (2 << 20)) << "the file is " << size << " bytes";
  before = testing::ProcessBytesRead();
  const workflow::CsvLayout layout =
      workflow::CheckCsvLayout(path, {}, *source, planned.options, workflow::CountCsvDataRows(path), nullptr);
  workflow::FitCsvFile(path, {}, *source, plan, layout);
  EXPECT_GE(static_cast<double>(testing::ProcessBytesRead() - before), 2.4 * size);
}

}  // namespace
}  // namespace ident
