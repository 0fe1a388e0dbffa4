#include "ident/workflow/polynomial_order_selection.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <vector>

#include "common/error.h"
#include "ident/workflow/predictions.h"

namespace ident::workflow {
namespace {

// Mean square of y − ŷ over the rows of the segment at least `t0` rows after its start and after the start of
// their experiment where both are finite, and their number.
std::pair<double, int> OneStepLoss(const SegmentPredictions& p, const io::DataTable& data, int t0) {
  double sum = 0;
  int n = 0;
  std::size_t first = 0;  // the current experiment's first row in the segment
  for (std::size_t i = 0; i < p.measured.size(); ++i) {
    if (i > 0 && data.StartsExperiment(p.rows[i] - 1)) first = i;
    if (i - first < static_cast<std::size_t>(t0)) continue;
    if (std::isfinite(p.one_step[i]) && std::isfinite(p.measured[i])) {
      const double e = p.measured[i] - p.one_step[i];
      sum += e * e;
      ++n;
    }
  }
  return {n > 0 ? sum / n : std::numeric_limits<double>::quiet_NaN(), n};
}

}  // namespace

OrderSelection SelectPolynomialOrders(const io::DataTable& table, const std::string& name,
                                      const PolynomialOrderGrid& grid, FitRequest request,
                                      const std::string& criterion) {
  IDENT_REQUIRE(
      criterion == "aic" || criterion == "bic" || criterion == "fpe" || criterion == "mdl" || criterion == "validation",
      "--criterion '{}': need aic, bic, fpe, mdl or validation", criterion);
  IDENT_REQUIRE(criterion != "validation" || request.split < 1,
                "--criterion validation needs a validation part (--split below 1)");
  IDENT_REQUIRE(grid.nc_min >= 0 && grid.nd_min >= 0 && grid.nf_min >= 0,
                "orders: need nc, nd, nf >= 0 (got nc {}:{}, nd {}:{}, nf {}:{})", grid.nc_min, grid.nc_max,
                grid.nd_min, grid.nd_max, grid.nf_min, grid.nf_max);
  const long structures = static_cast<long>(grid.arx.na_max - grid.arx.na_min + 1) *
                          (grid.arx.nb_max - grid.arx.nb_min + 1) * (grid.arx.nk_max - grid.arx.nk_min + 1) *
                          (grid.nc_max - grid.nc_min + 1) * (grid.nd_max - grid.nd_min + 1) *
                          (grid.nf_max - grid.nf_min + 1);
  IDENT_REQUIRE(structures <= 10'000,
                "orders: the grid has {} ARMAX/OE/BJ structures, each a recursive fit; at most 10000", structures);
  request.residual_lags = 0;
  // The structures of the grid that are models, and the largest first regression row among them.
  std::vector<ModelSpec> specs;
  int t0 = 0;
  for (int nk = grid.arx.nk_min; nk <= grid.arx.nk_max; ++nk)
    for (int na = grid.arx.na_min; na <= grid.arx.na_max; ++na)
      for (int nb = grid.arx.nb_min; nb <= grid.arx.nb_max; ++nb)
        for (int nc = grid.nc_min; nc <= grid.nc_max; ++nc)
          for (int nd = grid.nd_min; nd <= grid.nd_max; ++nd)
            for (int nf = grid.nf_min; nf <= grid.nf_max; ++nf) {
              ModelSpec spec = request.model;
              spec.na = na;
              spec.nb = {nb};
              spec.nk = {nk};
              spec.nc = nc;
              spec.nd = nd;
              spec.nf = nf;
              try {
                const std::unique_ptr<DataSource> source = spec.MakeSource(table.names, name);
                t0 = std::max(t0, source->first_regression_index());
              } catch (const InvalidArgument&) {
                continue;  // no model: an A polynomial with F, D without F, RPEM for Box–Jenkins
              }
              specs.push_back(std::move(spec));
            }
  IDENT_REQUIRE(!specs.empty(), "orders: no structure of the grid is an ARMAX, OE or Box-Jenkins model");
  OrderSelection result;
  result.criterion = criterion;
  for (const ModelSpec& spec : specs) {
    request.model = spec;
    const RecordFit fit = FitRecord(table, name, request);
    std::unique_ptr<DataSource> source = spec.MakeSource(fit.prepared.names, name);
    const auto [loss, n] = OneStepLoss(PredictSegment(fit.prepared, fit.estimation, *source, fit.result.theta), fit.prepared, t0);
    StructureScore s;
    s.na = spec.na;
    s.nb = spec.nb[0];
    s.nk = spec.nk[0];
    s.nc = spec.nc;
    s.nd = spec.nd;
    s.nf = spec.nf;
    s.n_parameters = static_cast<int>(fit.result.theta.size());
    s.theta = fit.result.theta;
    const double d = s.n_parameters;
    IDENT_REQUIRE(n > d + 1, "{}: {} scored estimation samples are too few for {} ({} parameters)", name, n,
                  source->structure(), s.n_parameters);
    result.samples = n;
    s.loss = loss;
    const double log_v = std::log(loss);
    s.aic = n * log_v + 2.0 * d;
    s.bic = n * log_v + d * std::log(static_cast<double>(n));
    s.fpe = loss * (1 + d / n) / (1 - d / n);
    s.mdl = loss * (1 + d * std::log(static_cast<double>(n)) / n);
    if (fit.validation.count > t0) {
      const auto [validation_loss, m] =
          OneStepLoss(PredictSegment(fit.prepared, fit.validation, *source, fit.result.theta), fit.prepared, t0);
      s.validation_loss = validation_loss;
      result.validation_samples = m;
    }
    result.structures.push_back(std::move(s));
  }
  std::stable_sort(result.structures.begin(), result.structures.end(),
                   [&criterion](const StructureScore& a, const StructureScore& b) {
                     const double x = CriterionValue(a, criterion), y = CriterionValue(b, criterion);
                     if (x != y) return x < y;
                     return a.n_parameters < b.n_parameters;
                   });
  return result;
}

}  // namespace ident::workflow
