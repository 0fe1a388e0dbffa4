#include "ident/workflow/smoothing_model.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>

#include <fmt/format.h>

#include "common/error.h"
#include "ident/io/csv.h"

namespace ident::workflow {
namespace {

using Json = nlohmann::json;
using models::Penalty;

[[noreturn]] void Fail(const std::string& where, const std::string& what) {
  throw InvalidArgument(fmt::format("{}: {}", where, what));
}

double Number(const Json& j, const std::string& where) {
  if (!j.is_number()) Fail(where, fmt::format("expected a number, got {}", j.dump()));
  return j.get<double>();
}

// A matrix given as an array of rows; a number c means c I of size `square` (when square > 0).
Eigen::MatrixXd Matrix(const Json& j, const std::string& where, int square = 0) {
  if (j.is_number() && square > 0) return Number(j, where) * Eigen::MatrixXd::Identity(square, square);
  if (!j.is_array() || j.empty()) Fail(where, "expected a non-empty array of rows");
  const size_t rows = j.size();
  if (!j[0].is_array() || j[0].empty()) Fail(where, "expected an array of rows, e.g. [[1, 0], [0, 1]]");
  const size_t cols = j[0].size();
  Eigen::MatrixXd M(rows, cols);
  for (size_t i = 0; i < rows; ++i) {
    if (!j[i].is_array() || j[i].size() != cols)
      Fail(where, fmt::format("row {} has {} entries; row 0 has {}", i, j[i].is_array() ? j[i].size() : 0, cols));
    for (size_t k = 0; k < cols; ++k) M(i, k) = Number(j[i][k], fmt::format("{}[{}][{}]", where, i, k));
  }
  return M;
}

Eigen::VectorXd Vector(const Json& j, const std::string& where, bool allow_null_as = false, double null_value = 0) {
  if (!j.is_array() || j.empty()) Fail(where, "expected a non-empty array of numbers");
  Eigen::VectorXd v(j.size());
  for (size_t i = 0; i < j.size(); ++i)
    v(i) = allow_null_as && j[i].is_null() ? null_value : Number(j[i], fmt::format("{}[{}]", where, i));
  return v;
}

const Json& Field(const Json& j, const char* key, const std::string& where) {
  if (!j.contains(key)) Fail(where, fmt::format("missing \"{}\"", key));
  return j.at(key);
}

// A matrix or an array of matrices (time-varying).
std::vector<Eigen::MatrixXd> Matrices(const Json& j, const std::string& where) {
  if (j.is_array() && !j.empty() && j[0].is_array() && !j[0].empty() && j[0][0].is_array()) {
    std::vector<Eigen::MatrixXd> out;
    for (size_t t = 0; t < j.size(); ++t) out.push_back(Matrix(j[t], fmt::format("{}[{}]", where, t)));
    return out;
  }
  return {Matrix(j, where)};
}

}  // namespace

models::Penalty ParsePenalty(const Json& j, int dim, const std::string& where) {
  if (!j.is_object()) Fail(where, "expected a penalty object such as {\"penalty\": \"l1\"}");
  const Json& name_json = Field(j, "penalty", where);
  if (!name_json.is_string()) Fail(where + ".penalty", "expected a string");
  const std::string name = name_json.get<std::string>();
  const std::map<std::string, std::vector<std::string>> keys = {{"quadratic", {"covariance"}},
                                                                {"l1", {}},
                                                                {"huber", {"kappa"}},
                                                                {"vapnik", {"epsilon"}},
                                                                {"quantile", {"tau"}},
                                                                {"piecewise_linear", {"knots", "values"}},
                                                                {"box", {"lower", "upper", "M"}}};
  auto it = keys.find(name);
  if (it == keys.end())
    Fail(where + ".penalty", fmt::format("unknown penalty '{}' (known: quadratic, l1, huber, vapnik, quantile, "
                                         "piecewise_linear, box)",
                                         name));
  for (const auto& [key, _] : j.items())
    if (key != "penalty" && std::find(it->second.begin(), it->second.end(), key) == it->second.end())
      Fail(where, fmt::format("unknown key \"{}\" for penalty '{}'", key, name));
  const std::string w = where + ".";
  try {
    if (name == "quadratic") {
      const Eigen::MatrixXd C = Matrix(Field(j, "covariance", where), w + "covariance", dim);
      if (C.rows() != dim || C.cols() != dim)
        Fail(w + "covariance", fmt::format("is {}x{}; need {}x{}", C.rows(), C.cols(), dim, dim));
      return Penalty::Quadratic(C);
    }
    if (name == "l1") return Penalty::L1(dim);
    if (name == "huber") return Penalty::Huber(Number(Field(j, "kappa", where), w + "kappa"), dim);
    if (name == "vapnik") return Penalty::Vapnik(Number(Field(j, "epsilon", where), w + "epsilon"), dim);
    if (name == "quantile") return Penalty::Quantile(Number(Field(j, "tau", where), w + "tau"), dim);
    if (name == "piecewise_linear") {
      if (dim != 1) Fail(where, fmt::format("piecewise_linear is scalar but this residual has {} entries", dim));
      return Penalty::PiecewiseLinear(Vector(Field(j, "knots", where), w + "knots"),
                                      Vector(Field(j, "values", where), w + "values"));
    }
    const double inf = models::kInfinity;
    const Eigen::VectorXd lo = Vector(Field(j, "lower", where), w + "lower", true, -inf);
    const Eigen::VectorXd hi = Vector(Field(j, "upper", where), w + "upper", true, inf);
    if (lo.size() != dim || hi.size() != dim)
      Fail(where, fmt::format("lower/upper have {}/{} entries; need {}", lo.size(), hi.size(), dim));
    return Penalty::BoxMonitoring(lo, hi, Matrix(Field(j, "M", where), w + "M", dim));
  } catch (const InvalidArgument& e) {
    const std::string what = e.what();
    if (what.rfind(where, 0) == 0) throw;
    Fail(where, what);
  }
}

void ParseSmoothModel(const Json& model, const std::string& source, MapSmootherProblem* p) {
  if (!model.is_object()) Fail(source, "the model must be a JSON object with F, H, initial, process, measurement");
  for (const auto& [key, _] : model.items())
    if (key != "F" && key != "H" && key != "initial" && key != "process" && key != "measurement")
      Fail(source, fmt::format("unknown key \"{}\" (known: F, H, initial, process, measurement)", key));
  p->F = Matrices(Field(model, "F", source), source + ": F");
  p->H = Matrices(Field(model, "H", source), source + ": H");
  const int n = static_cast<int>(p->H[0].cols()), nz = static_cast<int>(p->H[0].rows());
  if (nz != p->z.rows())
    Fail(source, fmt::format("H has {} rows but the data have {} measurement columns", nz, p->z.rows()));
  for (size_t t = 0; t < p->F.size(); ++t)
    if (p->F[t].rows() != n || p->F[t].cols() != n)
      Fail(source + ": F", fmt::format("F[{}] is {}x{} but H has {} columns (the state dimension)", t, p->F[t].rows(),
                                       p->F[t].cols(), n));
  for (size_t t = 0; t < p->H.size(); ++t)
    if (p->H[t].rows() != nz || p->H[t].cols() != n)
      Fail(source + ": H", fmt::format("H[{}] is {}x{}; H[0] is {}x{}", t, p->H[t].rows(), p->H[t].cols(), nz, n));
  p->process = {ParsePenalty(Field(model, "initial", source), n, source + ": initial")};
  const Json& process = Field(model, "process", source);
  if (process.is_array())
    for (size_t t = 0; t < process.size(); ++t)
      p->process.push_back(ParsePenalty(process[t], n, fmt::format("{}: process[{}]", source, t)));
  else
    p->process.push_back(ParsePenalty(process, n, source + ": process"));
  if (process.is_array() && static_cast<int>(process.size()) != p->T())
    Fail(source + ": process", fmt::format("has {} penalties; need one or T = {} (w_1..w_T)", process.size(), p->T()));
  const Json& measurement = Field(model, "measurement", source);
  p->measurement.clear();
  if (measurement.is_array())
    for (size_t t = 0; t < measurement.size(); ++t)
      p->measurement.push_back(ParsePenalty(measurement[t], nz, fmt::format("{}: measurement[{}]", source, t)));
  else
    p->measurement.push_back(ParsePenalty(measurement, nz, source + ": measurement"));
  try {
    ValidateMapSmootherProblem(*p);
  } catch (const InvalidArgument& e) {
    Fail(source, e.what());
  }
}

MapSmootherProblem ReadSmoothProblem(const std::string& model_path, const std::string& data_path,
                                     const io::CsvOptions& csv) {
  std::error_code ec;
  if (std::filesystem::is_directory(model_path, ec))
    throw DataError(fmt::format("cannot read '{}': it is a directory", model_path));
  std::ifstream in(model_path);
  if (!in) throw DataError(fmt::format("cannot open '{}'", model_path));
  Json model;
  try {
    model = Json::parse(in);
  } catch (const Json::exception& e) {  // parse errors, and numbers beyond double (1e999)
    throw DataError(fmt::format("{}: not valid JSON ({})", model_path, e.what()));
  }
  const io::DataTable table = io::ReadCsv(data_path, csv);
  std::vector<int> cols;
  auto find = [&](const std::string& name) {
    auto it = std::find(table.names.begin(), table.names.end(), name);
    return it == table.names.end() ? -1 : static_cast<int>(it - table.names.begin());
  };
  if (find("z") >= 0) {
    cols.push_back(find("z"));
  } else {
    for (int i = 1; find(fmt::format("z{}", i)) >= 0; ++i) cols.push_back(find(fmt::format("z{}", i)));
  }
  if (cols.empty()) throw DataError(fmt::format("{}: no measurement column (need z, or z1, z2, ...)", data_path));
  MapSmootherProblem p;
  p.z.resize(cols.size(), table.num_rows());
  for (size_t i = 0; i < cols.size(); ++i) p.z.row(i) = table.values.col(cols[i]).transpose();
  if (!std::isfinite(p.z.squaredNorm()))  // the penalties square residuals of this size
    throw DataError(
        fmt::format("{}: the measurements' sum of squares is beyond 1e308 (values near 1e308?); "
                    "rescale the data",
                    data_path));
  ParseSmoothModel(model, model_path, &p);
  return p;
}

}  // namespace ident::workflow
