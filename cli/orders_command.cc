// ident orders DATA... [--experiment-column NAME] --output y --input u [--na 1:10] [--nb 1:10] [--nk 0:5] [--criterion aic|bic|fpe|mdl|validation]
//              [--estimator rls|cauchy|student:K [--dof K]] [--split 0.5] [--detrend mean|none] [--top N] [--json]
// ARX order and delay selection (ident/workflow/order_selection.h): every structure of the grid fitted by
// least squares on the same estimation samples, ranked by the criterion; with a robust estimator each
// structure is one recursive fit scored by its Student-t likelihood (ident/workflow/polynomial_order_selection.h).
#include <iostream>
#include <memory>
#include <optional>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <nlohmann/json.hpp>

#include "cli/commands.h"
#include "cli/csv_options.h"
#include "cli/estimator_options.h"
#include "cli/experiment_records.h"
#include "cli/progress.h"
#include "cli/time_gaps.h"
#include "common/error.h"
#include "ident/io/csv.h"
#include "ident/io/mat_file.h"
#include "ident/workflow/data_source.h"
#include "ident/workflow/order_selection.h"
#include "ident/workflow/polynomial_order_selection.h"

namespace ident::cli {
namespace {

struct OrdersOptions {
  std::vector<std::string> data;  // one record, or one file per experiment
  std::string experiment_column, output, input;
  bool missing = false;
  std::string na = "1:5", nb = "1:5", nk = "1:5";
  std::string nc = "0", nd = "0", nf = "0";  // ARMAX/OE/BJ ranges
  std::string recursion = "rplr";
  int passes = 3;
  std::string criterion = "aic";
  workflow::EstimatorSpec estimator;  // rls: least squares; cauchy, student:K: robust criteria
  double split = 0.5;
  std::string detrend = "mean";
  int top = 20;
  bool json = false;
  io::CsvOptions csv;
};

nlohmann::ordered_json Optional(const std::optional<double>& x) {
  return x ? nlohmann::ordered_json(*x) : nlohmann::ordered_json();
}

nlohmann::ordered_json ScoreJson(const workflow::StructureScore& s, bool robust) {
  nlohmann::ordered_json j;
  j["na"] = s.na;
  j["nb"] = s.nb;
  j["nk"] = s.nk;
  j["nc"] = s.nc;
  j["nd"] = s.nd;
  j["nf"] = s.nf;
  j["n_parameters"] = s.n_parameters;
  j["loss"] = s.loss;
  j["aic"] = s.aic;
  j["bic"] = s.bic;
  j["fpe"] = s.fpe;
  j["mdl"] = s.mdl;
  j["validation_loss"] = s.validation_loss ? nlohmann::ordered_json(*s.validation_loss) : nlohmann::ordered_json();
  if (robust) {
    j["nll"] = Optional(s.nll);
    j["scale"] = Optional(s.scale);
    j["validation_nll"] = Optional(s.validation_nll);
  }
  j["theta"] = std::vector<double>(s.theta.data(), s.theta.data() + s.theta.size());
  return j;
}

void RunOrders(const OrdersOptions& o) {
  std::vector<std::string> paths;
  for (const std::string& d : o.data) paths.push_back(ResolveDataPath(d));
  workflow::OrderGrid grid;
  std::tie(grid.na_min, grid.na_max) = workflow::OrderGrid::ParseRange(o.na, "--na");
  std::tie(grid.nb_min, grid.nb_max) = workflow::OrderGrid::ParseRange(o.nb, "--nb");
  std::tie(grid.nk_min, grid.nk_max) = workflow::OrderGrid::ParseRange(o.nk, "--nk");
  IDENT_REQUIRE(grid.na_min >= 0 && grid.nb_min >= 1 && grid.nk_min >= 0,
                "orders: need na >= 0, nb >= 1 and nk >= 0 (got --na {} --nb {} --nk {})", o.na, o.nb, o.nk);
  workflow::PolynomialOrderGrid polynomial{grid};
  std::tie(polynomial.nc_min, polynomial.nc_max) = workflow::OrderGrid::ParseRange(o.nc, "--nc");
  std::tie(polynomial.nd_min, polynomial.nd_max) = workflow::OrderGrid::ParseRange(o.nd, "--nd");
  std::tie(polynomial.nf_min, polynomial.nf_max) = workflow::OrderGrid::ParseRange(o.nf, "--nf");
  const bool with_noise_model = polynomial.nc_max > 0 || polynomial.nd_max > 0 || polynomial.nf_max > 0;
  IDENT_REQUIRE(o.passes >= 1 && o.passes <= 100, "--passes {}; need 1..100", o.passes);
  const std::optional<double> dof = workflow::OrderCriterionDof(o.estimator);  // a robust estimator's k
  IDENT_REQUIRE(!dof || o.criterion != "fpe",
                "--criterion fpe is not likelihood-based; with --estimator {} use aic, "
                "bic, mdl or validation",
                o.estimator.estimator);
  const EstimatorSettings spec = ParseEstimatorSpec(o.estimator.estimator);
  if (!dof && !with_noise_model) {  // the ARX grid's least squares are batch solves: no recursion to set up
    const std::string setting = !spec.first_regression_setting().empty() ? spec.first_regression_setting()
                                : !spec.options.empty()                  ? spec.options.begin()->first
                                                                         : std::string();
    IDENT_REQUIRE(setting.empty(),
                  "orders --estimator '{}': {} does not apply to the ARX grid's least-squares fits (give plain rls)",
                  o.estimator.estimator, setting);
  }
  const std::string estimator_name = !dof                    ? "rls"
                                     : spec.name == "cauchy" ? "cauchy"
                                                             : fmt::format("student:{:g}", *dof);
  // Several experiments (several files, an experiment column) in one table, as ident fit reads them: no
  // regressor straddles two. The time column of a single record is checked (its gaps filled with --missing).
  ExperimentRecords records =
      ReadExperimentRecords(paths, o.experiment_column, {.missing_as_nan = o.missing, .delimiter = o.csv.delimiter});
  io::DataTable& table = records.table;
  const std::string path = records.name;
  // The largest structure's source: it reads the output and the input, and splits and detrends them.
  const models::ArxStructure largest(grid.na_max, {grid.nb_max}, {grid.nk_max});
  std::unique_ptr<workflow::DataSource> source =
      workflow::MakeArxSource(table.names, o.output, {o.input}, largest, path);
  std::optional<workflow::TimeCheck> time;
  if (!records.several) time = workflow::CheckRecordTime(table, source->used_columns(), o.missing);
  std::optional<io::DataTable> raw;  // the ARMAX/OE/BJ grid fits each structure from the record as read
  if (with_noise_model || dof) raw = table;
  workflow::FitOptions options;
  options.split = o.split;
  options.detrend = o.detrend == "none" ? workflow::Detrend::kNone : workflow::Detrend::kMean;
  const auto [estimation, validation] = workflow::PrepareData(table, *source, options);
  Progress progress("orders");  // on stderr after 2 s: the rows, then the structures
  workflow::OrderSelection r;
  if (with_noise_model || dof) {
    workflow::FitRequest request;
    request.estimator = o.estimator;
    request.model.output = o.output;
    request.model.inputs = {o.input};
    request.model.recursion = o.recursion;
    request.split = o.split;
    request.passes = o.passes;
    request.detrend = o.detrend;
    r = workflow::SelectPolynomialOrders(
        *raw, path, polynomial, request, o.criterion,
        [&progress](long done, long total, const char* unit) { progress.Report(done, total, unit); });
  } else {
    r = workflow::SelectOrders(
        table, estimation, o.split < 1 ? validation : workflow::Segment{}, table.ColumnIndex(o.output),
        table.ColumnIndex(o.input), grid, o.criterion,
        [&progress](long done, long total, const char* unit) { progress.Report(done, total, unit); });
  }
  if (o.json) {
    nlohmann::ordered_json j;
    j["data"] = path;
    j["criterion"] = r.criterion;
    if (dof) j["estimator"] = estimator_name;
    j["samples"] = r.samples;
    j["validation_samples"] = r.validation_samples;
    j["experiments"] = workflow::ExperimentsJson(records.experiments);
    j["time_gaps"] = workflow::TimeGapsJson(time);
    j["best"] = ScoreJson(r.structures.front(), dof.has_value());
    auto& list = j["structures"] = nlohmann::ordered_json::array();
    for (const auto& s : r.structures) list.push_back(ScoreJson(s, dof.has_value()));
    auto& left_out = j["left_out"] = nlohmann::ordered_json::array();
    for (const auto& [s, why] : r.left_out)
      left_out.push_back(
          {{"na", s.na}, {"nb", s.nb}, {"nk", s.nk}, {"nc", s.nc}, {"nd", s.nd}, {"nf", s.nf}, {"reason", why}});
    std::cout << j.dump(2) << "\n";
    return;
  }
  if (dof)
    fmt::print(
        "{}: {} structures (na {}, nb {}, nk {}{}) fitted by {} in {} passes, scored by the Student-t likelihood "
        "(k = {:g}) on the same {} samples{}\n",
        path, r.structures.size(), o.na, o.nb, o.nk,
        with_noise_model ? fmt::format(", nc {}, nd {}, nf {}", o.nc, o.nd, o.nf) : "", estimator_name, o.passes, *dof,
        r.samples, r.validation_samples ? fmt::format(", validated on {}", r.validation_samples) : "");
  else if (with_noise_model)
    fmt::print(
        "{}: {} structures (na {}, nb {}, nk {}, nc {}, nd {}, nf {}) fitted by {} in {} passes, scored on the same "
        "{} samples{}\n",
        path, r.structures.size(), o.na, o.nb, o.nk, o.nc, o.nd, o.nf, o.recursion, o.passes, r.samples,
        r.validation_samples ? fmt::format(", validated on {}", r.validation_samples) : "");
  else
    fmt::print("{}: {} ARX structures (na {}, nb {}, nk {}) fitted by least squares on the same {} samples{}\n", path,
               r.structures.size(), o.na, o.nb, o.nk, r.samples,
               r.validation_samples ? fmt::format(", validated on {}", r.validation_samples) : "");
  if (records.experiments.size() > 1) {
    PrintExperiments(records.experiments);
    fmt::print("\n");
  }
  if (time) PrintTimeGaps(stdout, *time, o.missing);
  fmt::print("ranked by {} (lower is better)\n\n", r.criterion);
  const std::size_t shown = std::min<std::size_t>(r.structures.size(), static_cast<std::size_t>(std::max(1, o.top)));
  const auto noise_orders = [&](auto nc, auto nd, auto nf) {
    return with_noise_model ? fmt::format(" {:>3} {:>3} {:>3}", nc, nd, nf) : std::string();
  };
  if (dof) {
    fmt::print("  {:>3} {:>3} {:>3}{} {:>4} {:>12} {:>12} {:>12} {:>12} {:>12} {:>12}{}\n", "na", "nb", "nk",
               noise_orders("nc", "nd", "nf"), "d", "loss", "scale", "NLL", "AIC", "BIC", "MDL",
               r.validation_samples ? fmt::format(" {:>14}", "validation NLL") : "");
    for (std::size_t i = 0; i < shown; ++i) {
      const auto& s = r.structures[i];
      fmt::print("  {:>3} {:>3} {:>3}{} {:>4} {:>12.6g} {:>12.6g} {:>12.6g} {:>12.6g} {:>12.6g} {:>12.6g}{}\n", s.na,
                 s.nb, s.nk, noise_orders(s.nc, s.nd, s.nf), s.n_parameters, s.loss, *s.scale, *s.nll, s.aic, s.bic,
                 s.mdl, s.validation_nll ? fmt::format(" {:>14.6g}", *s.validation_nll) : "");
    }
  } else {
    fmt::print("  {:>3} {:>3} {:>3}{} {:>4} {:>12} {:>12} {:>12} {:>12} {:>12}{}\n", "na", "nb", "nk",
               with_noise_model ? fmt::format(" {:>3} {:>3} {:>3}", "nc", "nd", "nf") : "", "d", "loss", "AIC", "BIC",
               "FPE", "MDL", r.validation_samples ? fmt::format(" {:>12}", "validation") : "");
    for (std::size_t i = 0; i < shown; ++i) {
      const auto& s = r.structures[i];
      fmt::print("  {:>3} {:>3} {:>3}{} {:>4} {:>12.6g} {:>12.6g} {:>12.6g} {:>12.6g} {:>12.6g}{}\n", s.na, s.nb, s.nk,
                 with_noise_model ? fmt::format(" {:>3} {:>3} {:>3}", s.nc, s.nd, s.nf) : "", s.n_parameters, s.loss,
                 s.aic, s.bic, s.fpe, s.mdl, s.validation_loss ? fmt::format(" {:>12.6g}", *s.validation_loss) : "");
    }
  }
  if (shown < r.structures.size()) fmt::print("  … {} more (--top, --json)\n", r.structures.size() - shown);
  if (!r.left_out.empty()) {
    const auto& [s, why] = r.left_out.front();
    fmt::print(
        "  {} structure{} left out, unusable (--json lists them), e.g. na {} nb {} nk {} nc {} nd {} nf {}: {}\n",
        r.left_out.size(), r.left_out.size() == 1 ? "" : "s", s.na, s.nb, s.nk, s.nc, s.nd, s.nf, why);
  }
  const auto& best = r.structures.front();
  const std::string fit_data = fmt::format("{}", fmt::join(o.data, " ")) +
                               (o.experiment_column.empty() ? "" : " --experiment-column " + o.experiment_column);
  const std::string fit_estimator = dof ? " --estimator " + o.estimator.estimator +
                                              (o.estimator.dof ? fmt::format(" --dof {:g}", *o.estimator.dof) : "")
                                        : "";
  if (with_noise_model)
    fmt::print("\nbest by {}: ident fit {} --output {} --input {} --na {} --nb {} --nk {} --nc {} --nd {} --nf {}{}\n",
               r.criterion, fit_data, o.output, o.input, best.na, best.nb, best.nk, best.nc, best.nd, best.nf,
               fit_estimator);
  else
    fmt::print("\nbest by {}: ARX({},{},{})  (ident fit {} --output {} --input {} --na {} --nb {} --nk {}{})\n",
               r.criterion, best.na, best.nb, best.nk, fit_data, o.output, o.input, best.na, best.nb, best.nk,
               fit_estimator);
}

}  // namespace

void AddOrdersCommand(CLI::App& app) {
  auto o = std::make_shared<OrdersOptions>();
  CLI::App* cmd =
      app.add_subcommand("orders", "Select ARX orders and delay: loss and AIC/BIC/FPE/MDL of every structure");
  AddDataFilesOptions(*cmd, o->data, o->experiment_column);
  AddMissingOption(*cmd, o->missing);
  cmd->add_option("--output", o->output, "Output column y")->required();
  cmd->add_option("--input", o->input, "Input column u (one input)")->required();
  cmd->add_option("--na", o->na, "Range of na, A:B or N")->capture_default_str();
  cmd->add_option("--nb", o->nb, "Range of nb (>= 1), A:B or N")->capture_default_str();
  cmd->add_option("--nk", o->nk, "Range of the delay nk, A:B or N")->capture_default_str();
  cmd->add_option("--nc", o->nc, "Range of the ARMAX/BJ noise numerator order nc, A:B or N (0: ARX)")
      ->capture_default_str();
  cmd->add_option("--nd", o->nd, "Range of the Box-Jenkins noise denominator order nd (with nf >= 1)")
      ->capture_default_str();
  cmd->add_option("--nf", o->nf,
                  "Range of the output-error/BJ denominator order nf (structures with nf > 0 have na = 0)")
      ->capture_default_str();
  cmd->add_option("--recursion", o->recursion, "ARMAX/OE/BJ grids: rplr or rpem")
      ->check(CLI::IsMember({"rplr", "rpem"}))
      ->capture_default_str();
  cmd->add_option("--passes", o->passes,
                  "ARMAX/OE/BJ grids and robust estimators: passes of the recursion per structure")
      ->capture_default_str();
  cmd->add_option("--criterion", o->criterion, "Rank by aic, bic, fpe, mdl or validation (loss on the validation part)")
      ->check(CLI::IsMember({"aic", "bic", "fpe", "mdl", "validation"}))
      ->capture_default_str();
  cmd->add_option("--estimator", o->estimator.estimator,
                  "rls (least squares), or cauchy / student:K: robust recursive fits ranked by the Student-t "
                  "likelihood (aic, bic, mdl, validation)")
      ->capture_default_str();
  cmd->add_option("--dof", o->estimator.dof, "Student-t degrees of freedom k (estimator student)");
  cmd->add_option("--split", o->split, "Fraction of rows used for estimation; the rest validate")
      ->capture_default_str();
  cmd->add_option("--detrend", o->detrend, "Subtract the estimation-part means (mean) or not (none)")
      ->check(CLI::IsMember({"mean", "none"}))
      ->capture_default_str();
  cmd->add_option("--top", o->top, "Rows of the table to print")->capture_default_str();
  cmd->add_flag("--json", o->json, "Print one JSON object {criterion, samples, best, structures: [...]}");
  AddDelimiterOption(*cmd, o->csv);
  cmd->callback([o] { RunOrders(*o); });
}

}  // namespace ident::cli
