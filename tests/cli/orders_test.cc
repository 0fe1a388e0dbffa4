// `ident orders` and workflow::SelectOrders: every structure's loss against its own least-squares fit on
// the same samples (an explicit regression matrix and a QR solve), the criteria by their definitions, the
// ranking, the JSON schema and bad input.
#include <cmath>
#include <string>

#include <gtest/gtest.h>
#include <Eigen/QR>
#include <nlohmann/json.hpp>

#include "common/dense_decompositions.h"
#include "common/error.h"
#include "ident/io/csv.h"
#include "ident/workflow/data_source.h"
#include "ident/workflow/order_selection.h"
#include "tests/support/cli.h"
#include "tests/support/test_data.h"

namespace ident::testing {
namespace {

struct Prepared {
  io::DataTable table;
  workflow::Segment estimation, validation;
};

Prepared Dryer(const workflow::OrderGrid& grid) {
  Prepared p{io::ReadCsv(DatasetPath("dryer.csv")), {}, {}};
  const models::ArxStructure largest(grid.na_max, {grid.nb_max}, {grid.nk_max});
  auto source = workflow::MakeArxSource(p.table.names, "y", {"u"}, largest, "dryer");
  std::tie(p.estimation, p.validation) = workflow::PrepareData(p.table, *source, {});
  return p;
}

// The regression of ARX(na, nb, nk) on rows t0 … of a segment, built directly from the columns.
void Regression(const Prepared& p, workflow::Segment s, int t0, int na, int nb, int nk, Eigen::MatrixXd& Z,
                Eigen::VectorXd& y) {
  const Eigen::VectorXd Y = p.table.Column("y"), U = p.table.Column("u");
  const int rows = s.count - t0;
  Z.resize(rows, na + nb);
  y.resize(rows);
  for (int i = 0; i < rows; ++i) {
    const int t = s.first + t0 + i;
    y(i) = Y(t);
    for (int k = 1; k <= na; ++k) Z(i, k - 1) = -Y(t - k);
    for (int k = 0; k < nb; ++k) Z(i, na + k) = U(t - nk - k);
  }
}

TEST(SelectOrders, EveryLossIsItsOwnLeastSquaresFitOnTheSameSamples) {
  const workflow::OrderGrid grid{1, 4, 1, 3, 0, 4};
  const Prepared p = Dryer(grid);
  const int y_col = p.table.ColumnIndex("y"), u_col = p.table.ColumnIndex("u");
  const workflow::OrderSelection r =
      workflow::SelectOrders(p.table, p.estimation, p.validation, y_col, u_col, grid, "aic");
  ASSERT_EQ(r.structures.size(), 4u * 3u * 5u);
  const int t0 = std::max(grid.na_max, grid.nk_max + grid.nb_max - 1);
  EXPECT_EQ(r.samples, p.estimation.count - t0);
  EXPECT_EQ(r.validation_samples, p.validation.count - t0);
  for (const auto& s : r.structures) {
    Eigen::MatrixXd Z, Zv;
    Eigen::VectorXd y, yv;
    Regression(p, p.estimation, t0, s.na, s.nb, s.nk, Z, y);
    Regression(p, p.validation, t0, s.na, s.nb, s.nk, Zv, yv);
    const Eigen::VectorXd theta = dense::ColPivQr(Z).solve(y);
    const double loss = (y - Z * theta).squaredNorm() / y.size();
    const std::string name =
        "ARX(" + std::to_string(s.na) + "," + std::to_string(s.nb) + "," + std::to_string(s.nk) + ")";
    EXPECT_NEAR(s.loss, loss, 1e-10 * loss) << name;
    EXPECT_LT((s.theta - theta).norm(), 1e-8 * theta.norm()) << name;
    EXPECT_NEAR(*s.validation_loss, (yv - Zv * theta).squaredNorm() / yv.size(), 1e-9 * loss) << name;
    const double n = r.samples, d = s.n_parameters;
    EXPECT_NEAR(s.aic, n * std::log(loss) + 2 * d, 1e-7) << name;
    EXPECT_NEAR(s.bic, n * std::log(loss) + d * std::log(n), 1e-7) << name;
    EXPECT_NEAR(s.fpe, loss * (n + d) / (n - d), 1e-10 * loss) << name;
    EXPECT_NEAR(s.mdl, loss * (1 + d * std::log(n) / n), 1e-10 * loss) << name;
  }
  for (std::size_t i = 1; i < r.structures.size(); ++i) EXPECT_LE(r.structures[i - 1].aic, r.structures[i].aic);
}

TEST(SelectOrders, RanksByTheChosenCriterion) {
  const workflow::OrderGrid grid{1, 3, 1, 3, 1, 3};
  const Prepared p = Dryer(grid);
  for (const std::string c : {"bic", "fpe", "mdl", "validation"}) {
    const auto r = workflow::SelectOrders(p.table, p.estimation, p.validation, p.table.ColumnIndex("y"),
                                          p.table.ColumnIndex("u"), grid, c);
    for (std::size_t i = 1; i < r.structures.size(); ++i)
      EXPECT_LE(workflow::CriterionValue(r.structures[i - 1], c), workflow::CriterionValue(r.structures[i], c)) << c;
  }
}

TEST(OrdersCommand, JsonListsEveryStructureBestFirst) {
  const CliResult r = RunCli("orders dryer --output y --input u --na 1:3 --nb 1:2 --nk 2:3 --criterion bic --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  ASSERT_EQ(j["structures"].size(), 12u);
  EXPECT_EQ(j["criterion"], "bic");
  EXPECT_EQ(j["best"], j["structures"][0]);
  for (const char* key : {"na", "nb", "nk", "n_parameters", "loss", "aic", "bic", "fpe", "mdl"})
    EXPECT_TRUE(j["best"].contains(key)) << key;
  EXPECT_EQ(j["best"]["n_parameters"], j["best"]["na"].get<int>() + j["best"]["nb"].get<int>());
}

TEST(OrdersCommand, BadInputExitsOneWithOneLine) {
  for (const auto& [args, message] : std::vector<std::pair<std::string, std::string>>{
           {"orders dryer --output y --input u --na 3:1", "--na '3:1': the range is empty"},
           {"orders dryer --output y --input u --nb 0:2", "need na >= 0, nb >= 1 and nk >= 0"},
           {"orders dryer --output y --input u --nk x", "--nk 'x': need N or A:B"},
           {"orders dryer --output y --input u --split 1 --criterion validation", "needs a validation part"},
           {"orders dryer --output y --input q", "no column 'q'"},
       }) {
    const CliResult r = RunCli(args);
    EXPECT_EQ(r.exit_code, 1) << args;
    EXPECT_NE(r.err.find(message), std::string::npos) << args << ": " << r.err;
  }
}

}  // namespace
}  // namespace ident::testing
