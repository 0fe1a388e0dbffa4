// The shared spec vectors reproduced column by column through the library [spec §10.11, §10.12].
#include <gtest/gtest.h>

#include "tests/regression/spec_vectors.h"

namespace ident {
namespace {

using testing::ReadSpecVector;
using testing::SpecVector;
using testing::VectorClose;

class SharedVector : public ::testing::TestWithParam<std::string> {};

TEST_P(SharedVector, LibraryReproducesEveryColumn) {
  const SpecVector v = ReadSpecVector(GetParam());
  ASSERT_EQ(v.rows.rows(), 1000);
  StudentRegression est(v.rho, v.Options());
  const int c_y = v.col("y"), c_z = v.col("z1"), c_theta = v.col("theta1");
  const std::vector<std::pair<std::string, std::function<double(const StepReport&)>>> step_columns = {
      {"nu", [](const StepReport& r) { return r.nu; }},
      {"beta", [](const StepReport& r) { return r.weight; }},
      {"pred_err", [](const StepReport& r) { return r.prediction_error; }},
      {"xi", [&](const StepReport&) { return est.last_step().xi; }},
      {"xi_z", [&](const StepReport&) { return est.last_step().xi_z; }},
      {"beta0", [&](const StepReport&) { return est.last_step().beta0; }},
      {"beta_hi", [&](const StepReport&) { return est.last_step().beta_hi; }},
  };
  int failures = 0;
  double worst_beta = 0;
  for (Eigen::Index t = 0; t < v.rows.rows(); ++t) {
    const Eigen::VectorXd z = v.rows.row(t).segment(c_z, v.rho).transpose();
    const StepReport r = est.Update(v.rows(t, c_y), z);
    ASSERT_EQ(r.status, StepStatus::kUpdated) << "t = " << t + 1;
    for (const auto& [name, get] : step_columns) {
      const double expected = v.rows(t, v.col(name)), got = get(r);
      if (!VectorClose(got, expected) && failures++ < 10)
        ADD_FAILURE() << GetParam() << " t = " << t + 1 << " " << name << ": " << got << " vs " << expected;
    }
    worst_beta = std::max(worst_beta, std::abs(r.weight / v.rows(t, v.col("beta")) - 1));
    for (int i = 0; i < v.rho; ++i) {
      const double expected = v.rows(t, c_theta + i), got = est.parameters()(i);
      if (!VectorClose(got, expected) && failures++ < 10)
        ADD_FAILURE() << GetParam() << " t = " << t + 1 << " theta" << i + 1 << ": " << got << " vs " << expected;
    }
    if (!VectorClose(est.Dy(), v.rows(t, v.col("Dy"))) && failures++ < 10)
      ADD_FAILURE() << GetParam() << " t = " << t + 1 << " Dy: " << est.Dy() << " vs " << v.rows(t, v.col("Dy"));
  }
  EXPECT_EQ(failures, 0);
  EXPECT_LT(worst_beta, 1e-11) << "max relative error of beta";
}

INSTANTIATE_TEST_SUITE_P(Spec, SharedVector, ::testing::ValuesIn(testing::SharedVectorNames()));

}  // namespace
}  // namespace ident
