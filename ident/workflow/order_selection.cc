#include "ident/workflow/order_selection.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "common/dense_decompositions.h"
#include "common/error.h"

namespace ident::workflow {
namespace {

// The lag layout of w(t): index 0 is y(t); 1 … na_max are −y(t−1) … −y(t−na_max); then u(t−k) for
// k = nk_min … nk_max + nb_max − 1.
struct Layout {
  int na_max, nk_min, u_lags;  // u_lags = nk_max + nb_max − nk_min
  int size() const { return 1 + na_max + u_lags; }
  int y_lag(int i) const { return i; }                          // −y(t−i), i ≥ 1
  int u_lag(int k) const { return 1 + na_max + (k - nk_min); }  // u(t−k)
  int max_lag() const { return std::max(na_max, nk_min + u_lags - 1); }
};

// w(t) for row r of the segment (r ≥ first + max_lag); false if any entry is not finite.
bool Lagged(const io::DataTable& data, int r, int output, int input, const Layout& l, Eigen::VectorXd& w) {
  w(0) = data.values(r, output);
  for (int i = 1; i <= l.na_max; ++i) w(l.y_lag(i)) = -data.values(r - i, output);
  for (int k = l.nk_min; k < l.nk_min + l.u_lags; ++k) w(l.u_lag(k)) = data.values(r - k, input);
  return w.allFinite();
}

// Calls each(r) for the rows r of the segment at least t0 rows after its start and after the start of r's
// experiment: the rows whose lags all lie in their own experiment.
template <class Each>
void ForRegressionRows(const io::DataTable& data, Segment segment, int t0, Each each) {
  int first = segment.first;  // the first row of the current experiment within the segment
  for (int r = segment.first; r < segment.first + segment.count; ++r) {
    if (r > segment.first && data.StartsExperiment(r)) first = r;
    if (r - first >= t0) each(r);
  }
}

std::vector<int> StructureIndices(const Layout& l, int na, int nb, int nk) {
  std::vector<int> idx;
  for (int i = 1; i <= na; ++i) idx.push_back(l.y_lag(i));
  for (int k = nk; k < nk + nb; ++k) idx.push_back(l.u_lag(k));
  return idx;
}

// Throws InvalidArgument unless the criterion is known and the ranges of the ARX grid are usable.
void CheckArxGrid(const OrderGrid& grid, const std::string& criterion, Segment validation) {
  IDENT_REQUIRE(
      criterion == "aic" || criterion == "bic" || criterion == "fpe" || criterion == "mdl" || criterion == "validation",
      "--criterion '{}': need aic, bic, fpe, mdl or validation", criterion);
  IDENT_REQUIRE(grid.na_min >= 0 && grid.nb_min >= 1 && grid.nk_min >= 0,
                "orders: need na >= 0, nb >= 1 and nk >= 0 (got na {}:{}, nb {}:{}, nk {}:{})", grid.na_min,
                grid.na_max, grid.nb_min, grid.nb_max, grid.nk_min, grid.nk_max);
  IDENT_REQUIRE(grid.na_max <= 100 && grid.nb_max <= 100 && grid.nk_max <= 1000,
                "orders: at most na 100, nb 100, nk 1000 (got {}, {}, {})", grid.na_max, grid.nb_max, grid.nk_max);
  IDENT_REQUIRE(criterion != "validation" || validation.count > 0,
                "--criterion validation needs a validation part (--split below 1)");
}

// The Gram matrix Σ w(t) w(t)' over the regression rows of `segment` whose lags are all finite (their number
// in *samples), reporting progress as rows `done_before` + 1 … of `rows`.
Eigen::MatrixXd RegressionGram(const io::DataTable& prepared, Segment segment, int t0, int output, int input,
                               const Layout& layout,
                               const std::function<void(long done, long total, const char* unit)>& progress,
                               long done_before, long rows, int* samples) {
  Eigen::MatrixXd G = Eigen::MatrixXd::Zero(layout.size(), layout.size());
  Eigen::VectorXd w(layout.size());
  ForRegressionRows(prepared, segment, t0, [&](int r) {
    if (progress) progress(done_before + r - segment.first + 1, rows, "rows");
    if (!Lagged(prepared, r, output, input, layout, w)) return;
    G.selfadjointView<Eigen::Lower>().rankUpdate(w);
    ++*samples;
  });
  G = G.selfadjointView<Eigen::Lower>();
  return G;
}

// ARX(na, nb, nk) fitted by least squares from the estimation Gram matrix G (samples n) and its criteria;
// its validation loss from H when the validation part has samples. Throws if its regressors are collinear.
StructureScore ScoreArxStructure(const Eigen::MatrixXd& G, const Eigen::MatrixXd& H, const Layout& layout, int samples,
                                 int validation_samples, int na, int nb, int nk, const std::string& source) {
  const double n = samples;
  const std::vector<int> idx = StructureIndices(layout, na, nb, nk);
  const int d = static_cast<int>(idx.size());
  Eigen::MatrixXd Gzz(d, d);
  Eigen::VectorXd Gzy(d);
  for (int i = 0; i < d; ++i) {
    Gzy(i) = G(idx[i], 0);
    for (int j = 0; j < d; ++j) Gzz(i, j) = G(idx[i], idx[j]);
  }
  const Eigen::LLT<Eigen::MatrixXd> llt = dense::Llt(Gzz);
  IDENT_REQUIRE(llt.info() == Eigen::Success &&
                    llt.matrixL().toDenseMatrix().diagonal().minCoeff() > 1e-10 * std::sqrt(Gzz.diagonal().maxCoeff()),
                "{}: ARX({},{},{}) is not determined by the data (its regressors are collinear)", source, na, nb, nk);
  StructureScore s;
  s.na = na;
  s.nb = nb;
  s.nk = nk;
  s.n_parameters = d;
  s.theta = llt.solve(Gzy);
  s.loss = std::max(0.0, (G(0, 0) - Gzy.dot(s.theta)) / n);
  const double log_v = std::log(s.loss);
  s.aic = n * log_v + 2.0 * d;
  s.bic = n * log_v + d * std::log(n);
  s.fpe = s.loss * (1 + d / n) / (1 - d / n);
  s.mdl = s.loss * (1 + d * std::log(n) / n);
  if (validation_samples > 0) {
    Eigen::MatrixXd Hzz(d, d);
    Eigen::VectorXd Hzy(d);
    for (int i = 0; i < d; ++i) {
      Hzy(i) = H(idx[i], 0);
      for (int j = 0; j < d; ++j) Hzz(i, j) = H(idx[i], idx[j]);
    }
    const double sum = H(0, 0) - 2 * s.theta.dot(Hzy) + s.theta.dot(Hzz * s.theta);
    s.validation_loss = std::max(0.0, sum) / validation_samples;
  }
  return s;
}

}  // namespace

std::pair<int, int> OrderGrid::ParseRange(const std::string& text, const std::string& option) {
  const auto colon = text.find(':');
  auto number = [&](const std::string& s) {
    std::size_t used = 0;
    int v = -1;
    try {
      v = std::stoi(s, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    IDENT_REQUIRE(!s.empty() && used == s.size(), "{} '{}': need N or A:B with whole numbers", option, text);
    return v;
  };
  if (colon == std::string::npos) {
    const int v = number(text);
    return {v, v};
  }
  const int a = number(text.substr(0, colon)), b = number(text.substr(colon + 1));
  IDENT_REQUIRE(a <= b, "{} '{}': the range is empty (A > B)", option, text);
  return {a, b};
}

double CriterionValue(const StructureScore& s, const std::string& criterion) {
  if (criterion == "aic") return s.aic;
  if (criterion == "bic") return s.bic;
  if (criterion == "fpe") return s.fpe;
  if (criterion == "mdl") return s.mdl;
  const std::optional<double>& validation = s.nll ? s.validation_nll : s.validation_loss;
  return validation.value_or(std::numeric_limits<double>::infinity());
}

OrderSelection SelectOrders(const io::DataTable& prepared, Segment estimation, Segment validation, int output,
                            int input, const OrderGrid& grid, const std::string& criterion,
                            const std::function<void(long done, long total, const char* unit)>& progress) {
  CheckArxGrid(grid, criterion, validation);
  const Layout layout{grid.na_max, grid.nk_min, grid.nk_max + grid.nb_max - grid.nk_min};
  const int t0 = layout.max_lag();
  OrderSelection result;
  result.criterion = criterion;
  const long rows = estimation.count + validation.count;
  // G over the estimation samples. The validation part's Gram matrix H: a structure's residual sum of squares
  // there is H_yy − 2θ'H_zy + θ'H_zz θ, whatever the number of samples.
  const Eigen::MatrixXd G =
      RegressionGram(prepared, estimation, t0, output, input, layout, progress, 0, rows, &result.samples);
  const Eigen::MatrixXd H = RegressionGram(prepared, validation, t0, output, input, layout, progress, estimation.count,
                                           rows, &result.validation_samples);

  const int d_max = grid.na_max + grid.nb_max;
  IDENT_REQUIRE(result.samples > d_max + 1,
                "{}: {} usable estimation samples are too few for up to {} parameters (na {} + nb {})", prepared.source,
                result.samples, d_max, grid.na_max, grid.nb_max);
  const long structures = static_cast<long>(grid.nk_max - grid.nk_min + 1) * (grid.na_max - grid.na_min + 1) *
                          (grid.nb_max - grid.nb_min + 1);
  for (int nk = grid.nk_min; nk <= grid.nk_max; ++nk) {
    for (int na = grid.na_min; na <= grid.na_max; ++na) {
      for (int nb = grid.nb_min; nb <= grid.nb_max; ++nb) {
        result.structures.push_back(
            ScoreArxStructure(G, H, layout, result.samples, result.validation_samples, na, nb, nk, prepared.source));
        if (progress) progress(static_cast<long>(result.structures.size()), structures, "structures");
      }
    }
  }
  std::stable_sort(result.structures.begin(), result.structures.end(),
                   [&criterion](const StructureScore& a, const StructureScore& b) {
                     const double x = CriterionValue(a, criterion), y = CriterionValue(b, criterion);
                     if (x != y) return x < y;
                     return a.n_parameters < b.n_parameters;  // ties: the smaller model
                   });
  return result;
}

}  // namespace ident::workflow
