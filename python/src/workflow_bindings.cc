// The workflow layer as Python functions: fit and compare a table (ident/workflow/fit_record.h,
// compare_record.h), MAP smoothing from a model dict (ident/workflow/smoothing_model.h) and the log-concave
// density MLE. Results cross as the JSON text of the command line's --json plus numpy arrays;
// python/ident/ turns them into result objects.
#include <cmath>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <pybind11/eigen.h>
#include <pybind11/functional.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <nlohmann/json.hpp>

#include "common/error.h"
#include "ident/density/logconcave_mle.h"
#include "ident/io/csv.h"
#include "ident/smoothing/map_smoother.h"
#include "ident/workflow/compare_record.h"
#include "ident/workflow/experiments.h"
#include "ident/workflow/fit_record.h"
#include "ident/workflow/predictions.h"
#include "ident/workflow/smoothing_model.h"
#include "python/src/bindings.h"

namespace py = pybind11;

namespace ident::python {
namespace {

io::DataTable Table(const std::vector<std::string>& columns, Eigen::MatrixXd values, const std::string& name) {
  IDENT_REQUIRE(static_cast<Eigen::Index>(columns.size()) == values.cols(), "{}: {} column names for {} columns", name,
                columns.size(), values.cols());
  io::DataTable table;
  table.source = name;
  table.names = columns;
  table.values = std::move(values);
  return table;
}

// The keyword arguments of ident.fit/ident.compare that choose the model and the estimator options.
struct Options {
  workflow::ModelSpec model;
  workflow::EstimatorSpec estimator;
};

Options ReadOptions(const py::dict& kw) {
  Options o;
  workflow::ModelSpec& m = o.model;
  workflow::EstimatorSpec& e = o.estimator;
  for (const auto& [key_handle, value] : kw) {
    const std::string key = py::str(key_handle);
    if (value.is_none()) continue;
    if (key == "output")
      m.output = value.cast<std::string>();
    else if (key == "inputs")
      m.inputs = value.cast<std::vector<std::string>>();
    else if (key == "na")
      m.na = value.cast<int>();
    else if (key == "nb")
      m.nb = value.cast<std::vector<int>>();
    else if (key == "nk")
      m.nk = value.cast<std::vector<int>>();
    else if (key == "nc")
      m.nc = value.cast<int>();
    else if (key == "nd")
      m.nd = value.cast<int>();
    else if (key == "nf")
      m.nf = value.cast<int>();
    else if (key == "recursion")
      m.recursion = value.cast<std::string>();
    else if (key == "regressors")
      m.regressors = value.cast<std::vector<std::string>>();
    else if (key == "intercept")
      m.intercept = value.cast<bool>();
    else if (key == "clean_regressors")
      m.clean_regressors = value.cast<bool>() ? "on" : "off";
    else if (key == "clean_clip")
      m.cleaning.clip = value.cast<double>();
    else if (key == "clean_gross")
      m.cleaning.gross = value.cast<double>();
    else if (key == "clean_below")
      m.clean_below = value.cast<double>();
    else if (key == "estimator")
      e.estimator = value.cast<std::string>();
    else if (key == "dof")
      e.dof = value.cast<double>();
    else if (key == "delta")
      e.delta = value.cast<int>();
    else if (key == "forgetting")
      e.forgetting = value.cast<double>();
    else if (key == "stabilised")
      e.stabilised = value.cast<bool>();
    else if (key == "nu0")
      e.nu0 = value.cast<double>();
    else if (key == "vy0")
      e.vy0 = value.cast<double>();
    else if (key == "vz0")
      e.vz0 = value.cast<double>();
    else if (key == "prior")
      e.prior_file = value.cast<std::string>();
    else if (key == "exact")
      e.exact = value.cast<bool>();
    else if (key == "lock_in_window")
      e.lock_in_window = value.cast<int>();
    else if (key == "lock_in_threshold")
      e.lock_in_threshold = value.cast<double>();
    else if (key == "lock_in_restart")
      e.no_lock_in_restart = !value.cast<bool>();
    else if (key == "history_limit")
      e.history_limit = value.cast<long>();
    else
      throw InvalidArgument("unknown option '" + key + "'");
  }
  return o;
}

// One row per accepted update: the record's row, β(t), ν(t), the prediction error, θ̂ and its standard errors.
struct History {
  std::vector<double> row, weight, nu, prediction_error;
  std::vector<double> theta, theta_std;  // updates × ρ, row-major
};

py::array_t<double> Matrix(const std::vector<double>& flat, std::size_t columns) {
  const std::size_t rows = columns ? flat.size() / columns : 0;
  py::array_t<double> a({rows, columns});
  std::copy(flat.begin(), flat.end(), a.mutable_data());
  return a;
}

py::dict Fit(const std::vector<std::string>& columns, Eigen::MatrixXd values, const std::string& name, double split,
             int passes, const std::string& detrend, bool history, int residual_lags, const py::dict& kw,
             const std::string& experiment_column) {
  const Options o = ReadOptions(kw);
  workflow::FitRequest request;
  request.model = o.model;
  request.estimator = o.estimator;
  request.split = split;
  request.passes = passes;
  request.detrend = detrend;
  IDENT_REQUIRE(residual_lags >= 0, "residual_lags = {}; need 0 (no residual analysis) or more", residual_lags);
  request.residual_lags = residual_lags;
  io::DataTable table = Table(columns, std::move(values), name);
  std::vector<workflow::Experiment> experiments;
  if (!experiment_column.empty()) experiments = workflow::LabelExperiments(table, experiment_column);
  std::unique_ptr<workflow::DataSource> source = request.model.MakeSource(table.names, name);
  const int rho = source->num_parameters();
  // The time column is checked and its gaps reported as `ident fit` does (filled there with --missing).
  const std::optional<workflow::TimeCheck> time =
      experiments.empty() ? workflow::CheckTimeColumn(table, source->used_columns()) : std::nullopt;
  workflow::FitPlan plan = workflow::PlanFit(request, rho, workflow::EstimationRows(table.num_rows(), request.split));
  History h;
  if (history)
    plan.options.on_update = [&h, rho](int row, const StepReport& step, const AnyRegressionEstimator& e) {
      h.row.push_back(row + 1);
      h.weight.push_back(step.weight);
      h.nu.push_back(step.nu);
      h.prediction_error.push_back(step.prediction_error);
      const Eigen::VectorXd theta = e.parameters();
      const Eigen::VectorXd std_dev = e.covariance().diagonal().cwiseMax(0).cwiseSqrt();
      for (int i = 0; i < rho; ++i) {
        h.theta.push_back(theta(i));
        h.theta_std.push_back(std_dev(i));
      }
    };
  workflow::RecordFit fit;
  {
    py::gil_scoped_release release;
    fit = workflow::FitTable(std::move(table), *source, plan, request.residual_lags);
  }
  fit.result.time = time;
  if (!experiments.empty()) fit.experiments = experiments;
  const workflow::ResidualAnalysis* residuals = fit.residuals ? &*fit.residuals : nullptr;
  py::dict out;
  const auto means = workflow::DetrendMeans(fit);
  out["json"] =
      workflow::FitJson(fit.result, name, split, request.ResolvedDetrend(), residuals, &means, &fit.experiments).dump();
  if (history) {
    py::dict d;
    d["row"] = py::array_t<double>(static_cast<py::ssize_t>(h.row.size()), h.row.data());
    d["weight"] = py::array_t<double>(static_cast<py::ssize_t>(h.weight.size()), h.weight.data());
    d["nu"] = py::array_t<double>(static_cast<py::ssize_t>(h.nu.size()), h.nu.data());
    d["prediction_error"] =
        py::array_t<double>(static_cast<py::ssize_t>(h.prediction_error.size()), h.prediction_error.data());
    d["theta"] = Matrix(h.theta, static_cast<std::size_t>(rho));
    d["theta_std"] = Matrix(h.theta_std, static_cast<std::size_t>(rho));
    out["history"] = d;
  }
  return out;
}

// The validation part's measured, one-step and simulated outputs of θ, on the table prepared as Fit prepares it.
py::dict Predict(const std::vector<std::string>& columns, Eigen::MatrixXd values, const std::string& name, double split,
                 const std::string& detrend, const Eigen::VectorXd& theta, const py::dict& kw,
                 const std::string& experiment_column) {
  const Options o = ReadOptions(kw);
  workflow::FitRequest request;
  request.model = o.model;
  request.split = split;
  request.detrend = detrend;
  io::DataTable table = Table(columns, std::move(values), name);
  if (!experiment_column.empty()) workflow::LabelExperiments(table, experiment_column);
  std::unique_ptr<workflow::DataSource> source = request.model.MakeSource(table.names, name);
  IDENT_REQUIRE(theta.size() == source->num_parameters(), "theta has {} entries; the model has {} parameters",
                theta.size(), source->num_parameters());
  workflow::FitOptions options;
  options.split = split;
  options.detrend = request.ResolvedDetrend() == "none" ? workflow::Detrend::kNone : workflow::Detrend::kMean;
  // The operating point of the fit (workflow/fit.h FitOptions::robust_offset): the estimator's own.
  options.robust_offset = RegressionEstimatorTraits(ParseEstimatorSpec(o.estimator.estimator).name).robust;
  const workflow::Segment validation = workflow::PrepareData(table, *source, options).second;
  const workflow::SegmentPredictions p = workflow::PredictSegment(table, validation, *source, theta);
  py::dict predictions;
  predictions["row"] = py::array_t<int>(static_cast<py::ssize_t>(p.rows.size()), p.rows.data());
  predictions["measured"] = py::array_t<double>(static_cast<py::ssize_t>(p.measured.size()), p.measured.data());
  predictions["one_step"] = py::array_t<double>(static_cast<py::ssize_t>(p.one_step.size()), p.one_step.data());
  if (!p.simulation.empty())
    predictions["simulation"] = py::array_t<double>(static_cast<py::ssize_t>(p.simulation.size()), p.simulation.data());
  return predictions;
}

std::string Compare(const std::vector<std::string>& columns, Eigen::MatrixXd values, const std::string& name,
                    const std::vector<std::string>& estimators, const std::string& outliers, int trials, int jobs,
                    int passes, double split, const std::string& detrend, const py::dict& kw) {
  const Options o = ReadOptions(kw);
  IDENT_REQUIRE(o.estimator.estimator == "rls", "compare takes estimators=[...], not estimator=");
  workflow::CompareRequest request;
  request.model = o.model;
  request.options = o.estimator;
  request.estimators = estimators;
  request.outliers = workflow::OutlierSpec::Parse(outliers);
  request.trials = trials;
  IDENT_REQUIRE(jobs >= 1 && jobs <= 1024, "jobs = {}; need 1 <= jobs <= 1024", jobs);
  request.jobs = jobs;
  request.passes = passes;
  request.split = split;
  request.detrend = detrend;
  io::DataTable table = Table(columns, std::move(values), name);
  // The time column is checked and its gaps reported as `ident compare` does (filled there with --missing).
  const std::optional<workflow::TimeCheck> time =
      workflow::CheckTimeColumn(table, request.model.MakeSource(table.names, name)->used_columns());
  workflow::CompareResult result;
  {
    py::gil_scoped_release release;
    result = workflow::CompareRecord(std::move(table), name, request);
  }
  result.time = time;
  return workflow::CompareJson(result, name, request.outliers, trials, request.model.clean_regressors).dump();
}

py::dict Smooth(const std::string& model_json, const Eigen::MatrixXd& z) {
  MapSmootherProblem problem;
  problem.z = z;
  workflow::ParseSmoothModel(nlohmann::json::parse(model_json), "model", &problem);
  ValidateMapSmootherProblem(problem);
  MapSmootherResult r;
  {
    py::gil_scoped_release release;
    r = SolveMapSmoother(problem);
  }
  if (r.status != MapSmootherStatus::kConverged) throw DataError("MAP smoothing: " + r.message);
  py::dict d;
  d["x"] = Eigen::MatrixXd(r.x.transpose());
  d["u"] = Eigen::MatrixXd(r.u.transpose());
  d["y"] = Eigen::MatrixXd(r.y.transpose());
  d["primal"] = r.primal;
  d["dual"] = r.dual;
  d["gap"] = r.gap;
  d["relative_gap"] = r.relative_gap;
  d["iterations"] = r.iterations;
  d["max_abs_x_from_dual_difference"] = r.max_abs_x_difference;
  d["reconstruction_unique"] = r.reconstruction_unique;
  d["nonunique_reconstruction_steps"] = r.nonunique_steps;
  d["dual_infeasibility"] = r.dual_infeasibility;
  // The duality certificate, as `ident smooth --json` has it: primal − optimum ≤ gap + gap_error_bound.
  d["status"] = ToString(r.status);
  d["kkt_residual"] = r.kkt_residual;
  d["gap_error_bound"] = r.gap_error_bound;
  d["relative_gap_bound"] =
      std::isfinite(r.relative_gap_bound) ? py::object(py::float_(r.relative_gap_bound)) : py::none();
  return d;
}

py::dict LogConcave(const std::vector<double>& samples) {
  const approx::LogConcaveMle mle = approx::FitLogConcaveMle(samples);
  const approx::LogConcaveKkt kkt = approx::CheckKkt(mle);
  py::dict d;
  d["n"] = mle.n;
  d["x"] = mle.x;
  d["weights"] = mle.weights;
  d["phi"] = mle.phi;
  d["knots"] = mle.knots;
  d["knot_phi"] = mle.knot_phi;
  d["loglik"] = mle.loglik;
  d["iterations"] = mle.iterations;
  d["max_directional_derivative"] = kkt.max_directional_derivative;
  d["mass_error"] = kkt.mass_error;
  return d;
}

}  // namespace

void RegisterWorkflow(py::module_& m) {
  m.def("fit", &Fit, py::arg("columns"), py::arg("values"), py::arg("name"), py::arg("split"), py::arg("passes"),
        py::arg("detrend"), py::arg("history"), py::arg("residual_lags"), py::arg("options"),
        py::arg("experiment_column") = "");
  m.def("predict", &Predict, py::arg("columns"), py::arg("values"), py::arg("name"), py::arg("split"),
        py::arg("detrend"), py::arg("theta"), py::arg("options"), py::arg("experiment_column") = "");
  m.def("compare", &Compare, py::arg("columns"), py::arg("values"), py::arg("name"), py::arg("estimators"),
        py::arg("outliers"), py::arg("trials"), py::arg("jobs"), py::arg("passes"), py::arg("split"),
        py::arg("detrend"), py::arg("options"));
  m.def("smooth", &Smooth, py::arg("model_json"), py::arg("z"));
  m.def("logcondens", &LogConcave, py::arg("samples"));
  m.def(
      "read_csv",
      [](const std::string& path, bool missing) {
        io::DataTable t = io::ReadCsv(path, {.missing_as_nan = missing});
        return py::make_tuple(t.names, t.values);
      },
      py::arg("path"), py::arg("missing") = false);
}

}  // namespace ident::python
