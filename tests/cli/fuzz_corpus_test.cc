// Replays every committed fuzz corpus input (fuzz/corpus/<target>/, including the reproducers of
// past findings) through the same property checks the libFuzzer targets use, so the ordinary test
// suite (and its ASan+UBSan build) guards against regressions without clang.
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "fuzz/cli_property.h"
#include "fuzz/csv_property.h"
#include "fuzz/fit_differential_property.h"
#include "fuzz/grid_observer_property.h"
#include "fuzz/logcondens_property.h"
#include "fuzz/observer_property.h"
#include "fuzz/output_file_property.h"
#include "fuzz/prior_json_property.h"
#include "fuzz/rls_property.h"
#include "fuzz/smooth_model_property.h"
#include "fuzz/smoother_scaling_property.h"
#include "fuzz/student_property.h"

namespace ident::testing {
namespace {

using Property = std::string (*)(const std::uint8_t*, std::size_t);

// Runs `property` on every file of fuzz/corpus/<target>; returns how many there were.
int ReplayCorpus(const std::string& target, Property property) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::path("fuzz/corpus") / target;
  EXPECT_TRUE(fs::is_directory(dir)) << dir;
  int count = 0;
  for (const auto& entry : fs::directory_iterator(dir)) {
    std::ifstream in(entry.path(), std::ios::binary);
    const std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    EXPECT_EQ(property(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size()), "") << entry.path();
    ++count;
  }
  return count;
}

TEST(FuzzCorpus, CsvReaderPropertiesHoldOnEveryCommittedInput) {
  EXPECT_GE(ReplayCorpus("csv_fuzzer", &fuzz::CsvProperty), 10);
}

TEST(FuzzCorpus, PriorJsonReaderPropertiesHoldOnEveryCommittedInput) {
  EXPECT_GE(ReplayCorpus("prior_json_fuzzer", &fuzz::PriorJsonProperty), 9);
}

TEST(FuzzCorpus, RlsPropertiesHoldOnEveryCommittedInput) {
  EXPECT_GE(ReplayCorpus("rls_fuzzer", &fuzz::RlsProperty), 7);
}

TEST(FuzzCorpus, StudentPropertiesHoldOnEveryCommittedInput) {
  EXPECT_GE(ReplayCorpus("student_fuzzer", &fuzz::StudentProperty), 6);
}

TEST(FuzzCorpus, KalmanFilterPropertiesHoldOnEveryCommittedInput) {
  EXPECT_GE(ReplayCorpus("kalman_fuzzer", &fuzz::KalmanProperty), 10);
}

TEST(FuzzCorpus, LcGaussianFilterPropertiesHoldOnEveryCommittedInput) {
  EXPECT_GE(ReplayCorpus("lc_gaussian_fuzzer", &fuzz::LcGaussianProperty), 11);
}

// The first lc_gaussian_fuzzer finding (unbounded recursion in StandardTruncatedMoments on an interval
// that standardises to a = b = 0): a stack overflow before the fix, now the step is refused.
TEST(FuzzCorpus, LcGaussianStackOverflowReproducerHolds) {
  const std::string path = "fuzz/corpus/lc_gaussian_fuzzer/crash-stack-overflow-truncated-moments-empty-interval";
  std::ifstream in(path, std::ios::binary);
  ASSERT_TRUE(in) << path;
  const std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(fuzz::LcGaussianProperty(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size()), "");
}

TEST(FuzzCorpus, GridObserverPropertiesHoldOnEveryCommittedInput) {
  EXPECT_GE(ReplayCorpus("grid_observer_fuzzer", &fuzz::GridObserverProperty), 40);
}

TEST(FuzzCorpus, SmoothModelReaderPropertiesHoldOnEveryCommittedInput) {
  EXPECT_GE(ReplayCorpus("smooth_model_fuzzer", &fuzz::SmoothModelProperty), 14);
}

TEST(FuzzCorpus, SmootherScalingPropertiesHoldOnEveryCommittedInput) {
  EXPECT_GE(ReplayCorpus("smoother_scaling_fuzzer", &fuzz::SmootherScalingProperty), 12);
}

TEST(FuzzCorpus, LogConcaveMlePropertiesHoldOnEveryCommittedInput) {
  EXPECT_GE(ReplayCorpus("logcondens_fuzzer", &fuzz::LogcondensProperty), 14);
}

TEST(FuzzCorpus, CommandLinePropertiesHoldOnEveryCommittedInput) {
  EXPECT_GE(ReplayCorpus("cli_fuzzer", &fuzz::CliProperty), 12);
}

TEST(FuzzCorpus, FitDifferentialPropertiesHoldOnEveryCommittedInput) {
  EXPECT_GE(ReplayCorpus("fit_differential_fuzzer", &fuzz::FitDifferentialProperty), 10);
}

TEST(FuzzCorpus, OutputFilePropertiesHoldOnEveryCommittedInput) {
  EXPECT_GE(ReplayCorpus("output_file_fuzzer", &fuzz::OutputFileProperty), 12);
}

// The replay is only as strong as its checks: a corpus input that breaks each property on purpose.
TEST(FuzzCorpus, PropertiesFlagViolations) {
  // An accepted model whose problem has an H of the wrong width must be flagged by the independent check.
  MapSmootherProblem p;
  p.F = {Eigen::MatrixXd::Identity(2, 2)};
  p.H = {Eigen::MatrixXd::Ones(1, 2), Eigen::MatrixXd::Ones(1, 3)};
  p.z = Eigen::MatrixXd::Zero(1, 2);
  p.process = {models::Penalty::L1(2)};
  p.measurement = {models::Penalty::L1(1)};
  EXPECT_EQ(fuzz::SmoothModelProblemIsConsistent(p, 1, 1), "every H is finite nz x n");
  p.H.pop_back();
  EXPECT_EQ(fuzz::SmoothModelProblemIsConsistent(p, 1, 1), "");
  EXPECT_EQ(fuzz::SmoothModelProblemIsConsistent(p, 2, 1), "every H is finite nz x n");
}

}  // namespace
}  // namespace ident::testing
