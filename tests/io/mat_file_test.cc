// The .mat reader (ident/io/mat_file.h) on files libmatio writes here, v5 and v7.3: values read back
// bit for bit.
#include "ident/io/mat_file.h"

#include <cmath>
#include <limits>

#include <gtest/gtest.h>

#include "common/error.h"
#include "tests/support/cli.h"
#include "tests/support/mat_writer.h"

namespace ident::io {
namespace {

void ExpectMatError(const std::string& path, const std::string& needle, CsvOptions options = {}) {
  try {
    ReadDataFile(path, options);
    ADD_FAILURE() << "no error for " << path;
  } catch (const DataError& e) {
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << "message: " << e.what();
    EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos) << "message is not one line";
  }
}

TEST(MatFile, NamesEndingInMatAreMatFiles) {
  EXPECT_TRUE(IsMatFile("a/record.mat"));
  EXPECT_TRUE(IsMatFile("R.MAT"));
  EXPECT_FALSE(IsMatFile("record.csv"));
  EXPECT_FALSE(IsMatFile("mat"));
}

#if IDENT_HAVE_MATIO

using ::ident::testing::MatVariable;
using ::ident::testing::TempDir;
using ::ident::testing::WriteMatFile;

class MatVersions : public ::testing::TestWithParam<mat_ft> {
 protected:
  std::string Path(const std::string& name) const {
    return TempDir() + "/" + name + (GetParam() == MAT_FT_MAT73 ? "_v73.mat" : "_v5.mat");
  }
};

TEST_P(MatVersions, VectorsAndMatrixColumnsReadBitForBit) {
  ASSERT_TRUE(MatFilesSupported());
  const std::vector<double> u = {0.1, -2.5e-300, 3.0, 1.0 / 3.0, 1e300};
  const std::vector<double> y = {std::nextafter(1.0, 2.0), -0.0, 7.25, -1e-5, 42};
  const std::vector<double> x = {1, 2, 3, 4, 5, 10, 20, 30, 40, 50};  // 5x2, column-major
  const std::string path = Path("vectors");
  WriteMatFile(path, GetParam(),
               {{"u", {5, 1}, u},
                {"Ts", {1, 1}, {0.08}},                                  // a scalar: passed over
                {"y", {1, 5}, y},                                        // a row vector
                {"label", {1, 3}, {'a', 'b', 'c'}, MatVariable::kChar},  // text: passed over
                {"X", {5, 2}, x},
                {"k", {5, 1}, {1, -2, 3, -4, 5}, MatVariable::kInt32}});
  const DataTable t = ReadDataFile(path);
  // In the order libmatio lists the variables: as written (v5), by name (v7.3, HDF5).
  const std::vector<std::string> expected = GetParam() == MAT_FT_MAT73
                                                ? std::vector<std::string>{"X_1", "X_2", "k", "u", "y"}
                                                : std::vector<std::string>{"u", "y", "X_1", "X_2", "k"};
  ASSERT_EQ(t.names, expected);
  ASSERT_EQ(t.num_rows(), 5);
  for (int i = 0; i < 5; ++i) {
    EXPECT_EQ(t.values(i, t.ColumnIndex("u")), u[i]) << i;
    EXPECT_EQ(t.values(i, t.ColumnIndex("y")), y[i]) << i;
    EXPECT_EQ(t.values(i, t.ColumnIndex("X_1")), x[i]) << i;
    EXPECT_EQ(t.values(i, t.ColumnIndex("X_2")), x[5 + i]) << i;
    EXPECT_EQ(t.values(i, t.ColumnIndex("k")), (i % 2 ? -1 : 1) * (i + 1)) << i;
  }
  EXPECT_TRUE(std::signbit(t.values(1, t.ColumnIndex("y"))));  // -0.0 kept
}

TEST_P(MatVersions, BadVariablesAreOneLineErrors) {
  const std::string lengths = Path("lengths");
  WriteMatFile(lengths, GetParam(), {{"u", {4, 1}, {1, 2, 3, 4}}, {"y", {5, 1}, {1, 2, 3, 4, 5}}});
  ExpectMatError(lengths, "variable 'u' has 4 samples; 'y' has 5");
  const std::string complex = Path("complex");
  WriteMatFile(complex, GetParam(), {{"z", {3, 1}, {1, 2, 3}, MatVariable::kComplex}});
  ExpectMatError(complex, "variable 'z' is complex");
  const std::string cube = Path("cube");
  WriteMatFile(cube, GetParam(), {{"c", {2, 2, 2}, {1, 2, 3, 4, 5, 6, 7, 8}}});
  ExpectMatError(cube, "variable 'c' has 3 dimensions");
  const std::string text = Path("text");
  WriteMatFile(text, GetParam(), {{"s", {1, 2}, {'h', 'i'}, MatVariable::kChar}});
  ExpectMatError(text, "no numeric variable");
  const std::string nan = Path("nan");
  const double kNaN = std::numeric_limits<double>::quiet_NaN();
  WriteMatFile(nan, GetParam(), {{"y", {3, 1}, {1, kNaN, 3}}});
  ExpectMatError(nan, "variable 'y', row 2: nan is not a finite number (pass --missing");
  const DataTable t = ReadDataFile(nan, {.missing_as_nan = true});
  EXPECT_TRUE(std::isnan(t.values(1, 0)));
  EXPECT_EQ(t.values(2, 0), 3);
}

INSTANTIATE_TEST_SUITE_P(V5AndV73, MatVersions, ::testing::Values(MAT_FT_MAT5, MAT_FT_MAT73),
                         [](const auto& info) { return info.param == MAT_FT_MAT73 ? "v73" : "v5"; });

TEST(MatFile, MissingAndForeignFiles) {
  ExpectMatError("/nonexistent/x.mat", "cannot open '/nonexistent/x.mat'");
  ExpectMatError(::ident::testing::WriteFile("text.mat", "t,u\n1,2\n"), "as a MATLAB file (v5, v7 or v7.3)");
}

#endif

}  // namespace
}  // namespace ident::io
