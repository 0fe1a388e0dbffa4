#include "ident/workflow/polynomial_order_selection.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <vector>

#include "common/error.h"
#include "ident/workflow/fit.h"
#include "ident/workflow/predictions.h"
#include "ident/workflow/student_likelihood.h"

namespace ident::workflow {
namespace {

// The one-step residuals y − ŷ over the rows of the segment at least `t0` rows after its start and after the
// start of their experiment where both are finite.
std::vector<double> OneStepResiduals(const SegmentPredictions& p, const io::DataTable& data, int t0) {
  std::vector<double> residuals;
  std::size_t first = 0;  // the current experiment's first row in the segment
  for (std::size_t i = 0; i < p.measured.size(); ++i) {
    if (i > 0 && data.StartsExperiment(p.rows[i] - 1)) first = i;
    if (i - first < static_cast<std::size_t>(t0)) continue;
    if (std::isfinite(p.one_step[i]) && std::isfinite(p.measured[i]))
      residuals.push_back(p.measured[i] - p.one_step[i]);
  }
  return residuals;
}

double MeanSquare(const std::vector<double>& r) {
  double sum = 0;
  for (const double x : r) sum += x * x;
  return r.empty() ? std::numeric_limits<double>::quiet_NaN() : sum / static_cast<double>(r.size());
}

// Throws InvalidArgument unless the criterion suits the estimator and the split and the grid is usable; the
// degrees of freedom of the Student-t criteria (none: least squares).
std::optional<double> CheckPolynomialGrid(const PolynomialOrderGrid& grid, const FitRequest& request,
                                          const std::string& criterion) {
  IDENT_REQUIRE(
      criterion == "aic" || criterion == "bic" || criterion == "fpe" || criterion == "mdl" || criterion == "validation",
      "--criterion '{}': need aic, bic, fpe, mdl or validation", criterion);
  const std::optional<double> dof = OrderCriterionDof(request.estimator);
  IDENT_REQUIRE(!dof || criterion != "fpe",
                "--criterion fpe is not likelihood-based; with --estimator {} use aic, bic, mdl "
                "or validation",
                request.estimator.estimator);
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
  return dof;
}

// The structures of the grid that are models (`model` with the grid's orders), and in *t0 the largest first
// regression row among them.
std::vector<ModelSpec> PolynomialGridModels(const io::DataTable& table, const std::string& name,
                                            const PolynomialOrderGrid& grid, const ModelSpec& model, int* t0) {
  std::vector<ModelSpec> specs;
  for (int nk = grid.arx.nk_min; nk <= grid.arx.nk_max; ++nk)
    for (int na = grid.arx.na_min; na <= grid.arx.na_max; ++na)
      for (int nb = grid.arx.nb_min; nb <= grid.arx.nb_max; ++nb)
        for (int nc = grid.nc_min; nc <= grid.nc_max; ++nc)
          for (int nd = grid.nd_min; nd <= grid.nd_max; ++nd)
            for (int nf = grid.nf_min; nf <= grid.nf_max; ++nf) {
              ModelSpec spec = model;
              spec.na = na;
              spec.nb = {nb};
              spec.nk = {nk};
              spec.nc = nc;
              spec.nd = nd;
              spec.nf = nf;
              try {
                const std::unique_ptr<DataSource> source = spec.MakeSource(table.names, name);
                *t0 = std::max(*t0, source->first_regression_index());
              } catch (const InvalidArgument&) {
                continue;  // no model: an A polynomial with F, D without F
              }
              specs.push_back(std::move(spec));
            }
  return specs;
}

// A score that names the structure's orders (the figures to be filled in).
StructureScore OrdersOf(const ModelSpec& spec) {
  StructureScore s;
  s.na = spec.na;
  s.nb = spec.nb[0];
  s.nk = spec.nk[0];
  s.nc = spec.nc;
  s.nd = spec.nd;
  s.nf = spec.nf;
  return s;
}

// The structure request.model fitted by FitRecord and scored on its one-step residuals from row t0 on: loss,
// criteria (Student-t likelihood ones with `dof`), validation loss; the sample counts go to *result.
StructureScore ScorePolynomialStructure(const io::DataTable& table, const std::string& name, const FitRequest& request,
                                        int t0, const std::optional<double>& dof, OrderSelection* result) {
  const ModelSpec& spec = request.model;
  const RecordFit fit = FitRecord(table, name, request);
  std::unique_ptr<DataSource> source = spec.MakeSource(fit.prepared.names, name);
  const std::vector<double> residuals =
      OneStepResiduals(PredictSegment(fit.prepared, fit.estimation, *source, fit.result.theta), fit.prepared, t0);
  const double loss = MeanSquare(residuals);
  const int n = static_cast<int>(residuals.size());
  StructureScore s = OrdersOf(spec);
  s.n_parameters = static_cast<int>(fit.result.theta.size());
  s.theta = fit.result.theta;
  const double d = s.n_parameters;
  IDENT_REQUIRE(n > d + 1, "{}: {} scored estimation samples are too few for {} ({} parameters)", name, n,
                source->structure(), s.n_parameters);
  result->samples = n;
  s.loss = loss;
  const double log_n = std::log(static_cast<double>(n));
  if (dof) {
    // Student-t_k likelihood criteria with d + 1 parameters (θ and the scale γ): AIC = 2 NLL + 2(d+1)
    // (Akaike 1974), BIC = 2 NLL + (d+1) log N (Schwarz 1978), MDL = BIC/2 = NLL + (d+1)/2 · log N
    // (Rissanen's two-part code length in nats, which ranks as BIC does, as the least-squares
    // MDL = V (1 + d log N / N) ≈ V·exp(d log N / N) ranks as its BIC N log V + d log N does).
    const StudentProfile profile = ProfileStudentLikelihood(residuals, *dof);
    s.nll = profile.nll;
    s.scale = profile.scale;
    s.aic = 2 * profile.nll + 2 * (d + 1);
    s.bic = 2 * profile.nll + (d + 1) * log_n;
    s.mdl = s.bic / 2;
    s.fpe = std::numeric_limits<double>::quiet_NaN();  // not likelihood-based
  } else {
    const double log_v = std::log(loss);
    s.aic = n * log_v + 2.0 * d;
    s.bic = n * log_v + d * log_n;
    s.fpe = loss * (1 + d / n) / (1 - d / n);
    s.mdl = loss * (1 + d * log_n / n);
  }
  if (fit.validation.count > t0) {
    const std::vector<double> validation =
        OneStepResiduals(PredictSegment(fit.prepared, fit.validation, *source, fit.result.theta), fit.prepared, t0);
    s.validation_loss = MeanSquare(validation);
    if (dof) s.validation_nll = StudentNegLogLikelihood(validation, *dof, *s.scale);
    result->validation_samples = static_cast<int>(validation.size());
  }
  return s;
}

}  // namespace

std::optional<double> OrderCriterionDof(const EstimatorSpec& estimator) {
  const EstimatorSettings s = ParseEstimatorSpec(estimator.estimator);
  if (s.name == "rls") {
    IDENT_REQUIRE(!estimator.dof, "dof = {} does not apply to estimator 'rls'", estimator.dof.value_or(0));
    return std::nullopt;
  }
  IDENT_REQUIRE(
      s.name == "cauchy" || s.name == "student",
      "orders --estimator '{}': need rls, cauchy or student:K (the robust criteria are Student-t likelihoods)",
      estimator.estimator);
  if (s.name == "cauchy") return 1.0;
  const std::optional<double> dof = estimator.dof ? estimator.dof : s.dof;
  IDENT_REQUIRE(dof && std::isfinite(*dof) && *dof > 0,
                "orders --estimator student needs dof k > 0 (--dof 3 or student:3)");
  return dof;
}

OrderSelection SelectPolynomialOrders(const io::DataTable& table, const std::string& name,
                                      const PolynomialOrderGrid& grid, FitRequest request, const std::string& criterion,
                                      const std::function<void(long done, long total, const char* unit)>& progress) {
  const std::optional<double> dof = CheckPolynomialGrid(grid, request, criterion);
  request.residual_lags = 0;
  int t0 = 0;
  const std::vector<ModelSpec> specs = PolynomialGridModels(table, name, grid, request.model, &t0);
  IDENT_REQUIRE(!specs.empty(), "orders: no structure of the grid is an ARMAX, OE or Box-Jenkins model");
  OrderSelection result;
  result.criterion = criterion;
  for (const ModelSpec& spec : specs) {
    request.model = spec;
    try {
      result.structures.push_back(ScorePolynomialStructure(table, name, request, t0, dof, &result));
    } catch (const UnusableFit& e) {  // this structure's estimate is no model; the others still rank
      result.left_out.emplace_back(OrdersOf(spec), e.reason());
    }
    if (progress)
      progress(static_cast<long>(result.structures.size() + result.left_out.size()), static_cast<long>(specs.size()),
               "structures");
  }
  if (result.structures.empty())
    throw DataError(
        fmt::format("{}: no structure of the grid gave a usable fit (e.g. {})", name, result.left_out.front().second));
  std::stable_sort(result.structures.begin(), result.structures.end(),
                   [&criterion](const StructureScore& a, const StructureScore& b) {
                     const double x = CriterionValue(a, criterion), y = CriterionValue(b, criterion);
                     if (x != y) return x < y;
                     return a.n_parameters < b.n_parameters;
                   });
  return result;
}

}  // namespace ident::workflow
