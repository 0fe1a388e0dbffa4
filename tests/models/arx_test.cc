#include "models/arx.h"

#include <gtest/gtest.h>

#include "common/error.h"

namespace ident::models {
namespace {

TEST(ArxStructure, CountsParametersAndFirstRegressionIndex) {
  const ArxStructure a(2, {2}, {3});
  EXPECT_EQ(a.num_parameters(), 4);
  EXPECT_EQ(a.first_regression_index(), 4);  // max(2, 3 + 2 − 1)
  EXPECT_EQ(a.ToString(), "ARX(2,2,3)");
  EXPECT_EQ(a.ParameterNames(), (std::vector<std::string>{"a1", "a2", "b1", "b2"}));
  const ArxStructure miso(1, {2, 3}, {1, 0});
  EXPECT_EQ(miso.num_parameters(), 6);
  EXPECT_EQ(miso.first_regression_index(), 2);
  EXPECT_EQ(miso.ToString(), "ARX(1,[2,3],[1,0])");
  EXPECT_EQ(ArxStructure(0, {3}, {1}).ToString(), "FIR(0,3,1)");
}

TEST(ArxStructure, RejectsInvalidOrders) {
  EXPECT_THROW(ArxStructure(-1, {2}, {1}), InvalidArgument);
  EXPECT_THROW(ArxStructure(2, {-2}, {1}), InvalidArgument);
  EXPECT_THROW(ArxStructure(2, {2}, {-1}), InvalidArgument);
  EXPECT_THROW(ArxStructure(2, {2, 2}, {1}), InvalidArgument);
  EXPECT_THROW(ArxStructure(0, {0}, {1}), InvalidArgument);
}

// The streamed regressor equals the definition z(t) = [−y(t−1) … −y(t−na), u_i(t−nk_i) …] by indexing.
TEST(ArxRegressor, MatchesDirectIndexingForMisoWithDirectFeedthrough) {
  const ArxStructure s(2, {2, 1}, {1, 0});
  ArxRegressor reg(s);
  const int n = 20;
  Eigen::VectorXd y(n), u1(n), u2(n);
  for (int t = 0; t < n; ++t) {
    y(t) = 0.3 * t * t - t;
    u1(t) = std::sin(t);
    u2(t) = std::cos(2 * t);
  }
  Eigen::VectorXd z(5);
  for (int t = 0; t < n; ++t) {
    const bool ready = reg.Next(Eigen::Vector2d(u1(t), u2(t)), z);
    EXPECT_EQ(ready, t >= 2);
    if (ready) {
      Eigen::VectorXd expected(5);
      expected << -y(t - 1), -y(t - 2), u1(t - 1), u1(t - 2), u2(t);
      EXPECT_EQ(z, expected) << "t=" << t;
    }
    reg.PushOutput(y(t));
  }
  reg.Reset();
  EXPECT_FALSE(reg.Next(Eigen::Vector2d(1, 1), z));
}

TEST(ArxRegressor, RejectsMisuse) {
  ArxRegressor reg(ArxStructure(1, {1}, {1}));
  Eigen::VectorXd z(2);
  EXPECT_THROW(reg.Next(Eigen::Vector2d(1, 1), z), InvalidArgument);  // two inputs for one
  EXPECT_THROW(reg.PushOutput(1.0), InvalidArgument);                 // output before Next
}

TEST(StaticRegression, PutsTheInterceptFirst) {
  StaticRegression r{{"x1", "x2"}, true};
  Eigen::VectorXd z(3);
  r.Regressor(Eigen::Vector2d(4, 5), z);
  EXPECT_EQ(z, Eigen::Vector3d(1, 4, 5));
  EXPECT_EQ(r.ParameterNames(), (std::vector<std::string>{"intercept", "x1", "x2"}));
}

}  // namespace
}  // namespace ident::models
