// `ident fit --trace` reproduces the shared spec vectors column by column [spec §10.12, issue item 3]:
//   ident fit data.csv --output y --regressors z1,..,zρ --estimator cauchy --exact --detrend none
//             --split 1 --prior prior.json [--forgetting λ [--stabilised]] --trace out.csv
#include <fmt/format.h>
#include <gtest/gtest.h>

#include "tests/regression/spec_vectors.h"
#include "tests/support/cli.h"

namespace ident {
namespace {

using testing::CliResult;
using testing::ReadSpecVector;
using testing::RunCli;
using testing::SpecVector;
using testing::VectorClose;

std::string PriorJson(const RegressionPrior& p) {
  std::string s = fmt::format("{{\"nu0\": {:.17g}, \"V0\": [", p.nu0);
  for (int i = 0; i < p.V0.rows(); ++i) {
    s += i ? ", [" : "[";
    for (int j = 0; j < p.V0.cols(); ++j) s += fmt::format("{}{:.17g}", j ? ", " : "", p.V0(i, j));
    s += "]";
  }
  return s + "]}";
}

class SharedVectorCli : public ::testing::TestWithParam<std::string> {};

TEST_P(SharedVectorCli, FitTraceReproducesEveryColumn) {
  const SpecVector v = ReadSpecVector(GetParam());
  std::string data = "y";
  std::string regressors;
  for (int i = 1; i <= v.rho; ++i) {
    data += fmt::format(",z{}", i);
    regressors += fmt::format("{}z{}", i > 1 ? "," : "", i);
  }
  data += "\n";
  for (Eigen::Index t = 0; t < v.rows.rows(); ++t) {
    data += fmt::format("{:.17g}", v.rows(t, v.col("y")));
    for (int i = 0; i < v.rho; ++i) data += fmt::format(",{:.17g}", v.rows(t, v.col("z1") + i));
    data += "\n";
  }
  const std::string data_path = testing::WriteFile(GetParam() + ".csv", data);
  const std::string prior_path = testing::WriteFile(GetParam() + "_prior.json", PriorJson(v.Prior()));
  const std::string trace_path = testing::TempDir() + "/" + GetParam() + "_trace.csv";
  std::string args = fmt::format(
      "fit {} --output y --regressors {} --estimator cauchy --exact --detrend none --split 1 --prior {} "
      "--trace {} --json",
      data_path, regressors, prior_path, trace_path);
  const double lambda = v.init.at("lambda");
  if (lambda != 1) args += fmt::format(" --forgetting {:.17g}", lambda);
  if (v.stabilised()) args += " --stabilised";
  const CliResult r = RunCli(args);
  ASSERT_EQ(r.exit_code, 0) << r.err;

  std::vector<std::string> names;
  const Eigen::MatrixXd trace = testing::ReadCsvMatrix(trace_path, &names);
  ASSERT_EQ(trace.rows(), v.rows.rows());
  int compared = 0, failures = 0;
  for (std::size_t c = 0; c < names.size(); ++c) {
    for (Eigen::Index t = 0; t < trace.rows(); ++t) {
      const double expected = v.rows(t, v.col(names[c])), got = trace(t, static_cast<Eigen::Index>(c));
      ++compared;
      if (!VectorClose(got, expected) && failures++ < 10)
        ADD_FAILURE() << GetParam() << " t = " << t + 1 << " " << names[c] << ": " << got << " vs " << expected;
    }
  }
  EXPECT_EQ(failures, 0);
  EXPECT_EQ(compared, 1000 * (4 + v.rho + 1));  // t, nu, beta, pred_err, theta1..ρ, Dy
}

INSTANTIATE_TEST_SUITE_P(Spec, SharedVectorCli, ::testing::ValuesIn(testing::SharedVectorNames()));

TEST(FitCli, CauchyRejectsDofAndStudentNeedsIt) {
  const std::string args = " --output y --input u --na 2 --nb 2 --nk 3";
  CliResult r = RunCli("fit dryer" + args + " --estimator cauchy --dof 3");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("dof = 3 does not apply to estimator 'cauchy'"), std::string::npos) << r.err;
  r = RunCli("fit dryer" + args + " --estimator student");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("needs dof"), std::string::npos) << r.err;
  r = RunCli("fit dryer" + args + " --estimator cauchy --nu0 3 --vy0 1 --vz0 1");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("inadmissible"), std::string::npos) << r.err;
  r = RunCli("fit dryer" + args + " --estimator student --dof 3 --json");
  EXPECT_EQ(r.exit_code, 0) << r.err;
}

}  // namespace
}  // namespace ident
