#include "ident/workflow/saved_model.h"

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>

#include <fmt/format.h>

#include "common/error.h"
#include "ident/workflow/json_number.h"

namespace ident::workflow {
namespace {

using Json = nlohmann::json;
using OrderedJson = nlohmann::ordered_json;

OrderedJson Vector(const Eigen::VectorXd& v) {
  OrderedJson a = OrderedJson::array();
  for (double x : v) a.push_back(FiniteOrNull(x));
  return a;
}

// The value at `key` of `j`, or a DataError naming the file and the key.
const Json& At(const Json& j, const std::string& key, const std::string& source) {
  if (!j.is_object() || !j.contains(key))
    throw DataError(fmt::format("{}: no key \"{}\" (not an ident model?)", source, key));
  return j.at(key);
}

template <class T>
T Get(const Json& j, const std::string& key, const std::string& source) {
  try {
    return At(j, key, source).get<T>();
  } catch (const Json::exception&) {
    throw DataError(fmt::format("{}: \"{}\" has the wrong type", source, key));
  }
}

double GetNumber(const Json& j, const std::string& key, const std::string& source) {
  const Json& v = At(j, key, source);
  if (v.is_null()) return std::nan("");
  if (!v.is_number()) throw DataError(fmt::format("{}: \"{}\" is not a number", source, key));
  return v.get<double>();
}

Eigen::VectorXd ToVector(const Json& a, const std::string& key, const std::string& source) {
  if (!a.is_array()) throw DataError(fmt::format("{}: \"{}\" is not an array", source, key));
  Eigen::VectorXd v(static_cast<Eigen::Index>(a.size()));
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (!a[i].is_number() && !a[i].is_null())
      throw DataError(fmt::format("{}: \"{}\"[{}] is not a number", source, key, i));
    v(static_cast<Eigen::Index>(i)) = a[i].is_null() ? std::nan("") : a[i].get<double>();
  }
  return v;
}

Eigen::VectorXd GetVector(const Json& j, const std::string& key, const std::string& source) {
  return ToVector(At(j, key, source), key, source);
}

Eigen::VectorXd GetVector(const Json& rows, std::size_t index, const std::string& source) {
  return ToVector(rows.at(index), fmt::format("covariance[{}]", index), source);
}

// The "structure" object: a static regression or an ARX/ARMAX/OE/BJ structure.
ModelSpec ReadStructure(const Json& s, const std::string& source) {
  ModelSpec model;
  const std::string kind = Get<std::string>(s, "kind", source);
  model.output = Get<std::string>(s, "output", source);
  if (kind == "static") {
    model.regressors = Get<std::vector<std::string>>(s, "regressors", source);
    model.intercept = Get<bool>(s, "intercept", source);
  } else if (kind == "arx" || kind == "armax" || kind == "oe" || kind == "bj") {
    model.inputs = Get<std::vector<std::string>>(s, "inputs", source);
    model.na = Get<int>(s, "na", source);
    model.nb = Get<std::vector<int>>(s, "nb", source);
    model.nk = Get<std::vector<int>>(s, "nk", source);
    if (kind != "arx") {
      model.nc = Get<int>(s, "nc", source);
      model.nd = Get<int>(s, "nd", source);
      model.nf = Get<int>(s, "nf", source);
      if (!model.polynomial())
        throw DataError(fmt::format("{}: structure kind \"{}\" with nc = nd = nf = 0", source, kind));
    }
  } else {
    throw DataError(fmt::format("{}: structure kind \"{}\"; need arx, armax, oe, bj or static", source, kind));
  }
  return model;
}

// The "covariance" rows: rho × rho numbers.
Eigen::MatrixXd ReadCovariance(const Json& cov, Eigen::Index rho, const std::string& source) {
  if (!cov.is_array() || static_cast<Eigen::Index>(cov.size()) != rho)
    throw DataError(fmt::format("{}: \"covariance\" needs {} rows of {} numbers", source, rho, rho));
  Eigen::MatrixXd covariance(rho, rho);
  for (Eigen::Index r = 0; r < rho; ++r) {
    const Eigen::VectorXd row = GetVector(cov, static_cast<std::size_t>(r), source);
    if (row.size() != rho)
      throw DataError(fmt::format("{}: \"covariance\" row {} has {} numbers; need {}", source, r + 1, row.size(), rho));
    covariance.row(r) = row.transpose();
  }
  return covariance;
}

// The "detrend_means" object: {column: mean}, in its order.
std::vector<std::pair<std::string, double>> ReadDetrendMeans(const Json& means, const std::string& source) {
  if (!means.is_object()) throw DataError(fmt::format("{}: \"detrend_means\" is not an object", source));
  std::vector<std::pair<std::string, double>> out;
  for (const auto& item : means.items()) {
    if (!item.value().is_number())
      throw DataError(fmt::format("{}: detrend mean of '{}' is not a number", source, item.key()));
    out.emplace_back(item.key(), item.value().get<double>());
  }
  return out;
}

// The "data.files" list: path, rows and checksum of each file read.
std::vector<SavedModel::DataFile> ReadDataFiles(const Json& files, const std::string& source) {
  if (!files.is_array()) throw DataError(fmt::format("{}: \"data.files\" is not a list", source));
  std::vector<SavedModel::DataFile> out;
  for (const Json& f : files)
    out.push_back({.path = Get<std::string>(f, "path", source),
                   .checksum = Get<std::string>(f, "fnv1a64", source),
                   .rows = Get<long>(f, "rows", source)});
  return out;
}

// The validation part's fit (percent) and RMS, one-step and, unless null, simulation.
FitScores ReadValidationScores(const Json& fit, const Json& rms, const std::string& source) {
  FitScores scores;
  scores.one_step = GetNumber(fit, "one_step", source);
  scores.rms_one_step = GetNumber(rms, "one_step", source);
  if (!At(fit, "simulation", source).is_null()) {
    scores.simulation = GetNumber(fit, "simulation", source);
    scores.rms_simulation = GetNumber(rms, "simulation", source);
  }
  return scores;
}

}  // namespace

OrderedJson SavedModel::ToJson() const {
  OrderedJson j;
  j["format"] = "ident-model";
  j["version"] = 1;
  OrderedJson s;
  if (!model.regressors.empty()) {
    s["kind"] = "static";
    s["output"] = model.output;
    s["regressors"] = model.regressors;
    s["intercept"] = model.intercept;
  } else {
    // "arx", or "armax" / "oe" / "bj" with the orders of C, D and F too.
    s["kind"] = !model.polynomial() ? "arx" : model.nf == 0 ? "armax" : model.nc + model.nd == 0 ? "oe" : "bj";
    s["output"] = model.output;
    s["inputs"] = model.inputs;
    s["na"] = model.na;
    s["nb"] = model.nb;
    s["nk"] = model.nk;
    if (model.polynomial()) {
      s["nc"] = model.nc;
      s["nd"] = model.nd;
      s["nf"] = model.nf;
    }
  }
  j["structure"] = s;
  j["structure_name"] = structure_name;
  j["parameter_names"] = parameter_names;
  j["theta"] = Vector(theta);
  OrderedJson cov = OrderedJson::array();
  for (Eigen::Index r = 0; r < covariance.rows(); ++r) cov.push_back(Vector(covariance.row(r).transpose()));
  j["covariance"] = cov;
  j["theta_std"] = Vector(theta_std);
  j["noise_std"] = FiniteOrNull(noise_std);
  j["detrend"] = detrend;
  OrderedJson means = OrderedJson::object();
  for (const auto& [name, mean] : detrend_means) means[name] = mean;
  j["detrend_means"] = means;
  j["estimator"] = {{"name", estimator}, {"kind", kind}, {"passes", passes}};
  j["data"] = {{"path", data_path}, {"rows", data_rows}, {"fnv1a64", data_checksum}};
  OrderedJson files = OrderedJson::array();
  for (const DataFile& f : data_files) files.push_back({{"path", f.path}, {"rows", f.rows}, {"fnv1a64", f.checksum}});
  j["data"]["files"] = files;
  j["split"] = split;
  j["validation_rows"] = {validation.first + 1, validation.first + validation.count};
  j["fit_percent"] = {
      {"one_step", FiniteOrNull(validation_scores.one_step)},
      {"simulation", validation_scores.simulation ? FiniteOrNull(*validation_scores.simulation) : nullptr}};
  j["rms"] = {
      {"one_step", FiniteOrNull(validation_scores.rms_one_step)},
      {"simulation", validation_scores.rms_simulation ? FiniteOrNull(*validation_scores.rms_simulation) : nullptr}};
  return j;
}

SavedModel SavedModel::FromJson(const Json& j, const std::string& source) {
  if (!j.is_object() || j.value("format", "") != "ident-model")
    throw DataError(fmt::format(
        "{}: not an ident model (no \"format\": \"ident-model\"; write one with ident fit --save)", source));
  if (Get<int>(j, "version", source) != 1)
    throw DataError(fmt::format("{}: model version {} is not supported (this program reads version 1)", source,
                                Get<int>(j, "version", source)));
  SavedModel m;
  m.model = ReadStructure(At(j, "structure", source), source);
  m.structure_name = Get<std::string>(j, "structure_name", source);
  m.parameter_names = Get<std::vector<std::string>>(j, "parameter_names", source);
  m.theta = GetVector(j, "theta", source);
  if (!m.theta.allFinite()) throw DataError(fmt::format("{}: \"theta\" has entries that are not finite", source));
  m.theta_std = GetVector(j, "theta_std", source);
  m.covariance = ReadCovariance(At(j, "covariance", source), m.theta.size(), source);
  m.noise_std = GetNumber(j, "noise_std", source);
  m.detrend = Get<std::string>(j, "detrend", source);
  if (m.detrend != "mean" && m.detrend != "none")
    throw DataError(fmt::format("{}: \"detrend\" is \"{}\"; need mean or none", source, m.detrend));
  m.detrend_means = ReadDetrendMeans(At(j, "detrend_means", source), source);
  const Json& e = At(j, "estimator", source);
  m.estimator = Get<std::string>(e, "name", source);
  m.kind = Get<std::string>(e, "kind", source);
  m.passes = Get<int>(e, "passes", source);
  const Json& d = At(j, "data", source);
  m.data_path = Get<std::string>(d, "path", source);
  m.data_rows = Get<long>(d, "rows", source);
  m.data_checksum = Get<std::string>(d, "fnv1a64", source);
  if (d.contains("files")) m.data_files = ReadDataFiles(d["files"], source);
  m.split = GetNumber(j, "split", source);
  const auto rows = Get<std::vector<int>>(j, "validation_rows", source);
  if (rows.size() != 2) throw DataError(fmt::format("{}: \"validation_rows\" needs [first, last]", source));
  m.validation = {rows[0] - 1, rows[1] - rows[0] + 1};
  const Json& fit = At(j, "fit_percent", source);
  const Json& rms = At(j, "rms", source);
  m.validation_scores = ReadValidationScores(fit, rms, source);
  return m;
}

SavedModel SavedModel::Read(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    throw DataError(fmt::format("cannot read '{}': it is a directory", path));
  std::ifstream in(path);
  if (!in) throw DataError(fmt::format("cannot open model file '{}'", path));
  Json j;
  try {
    j = Json::parse(in);
  } catch (const Json::exception& e) {
    throw DataError(fmt::format("{}: not valid JSON ({})", path, e.what()));
  }
  return FromJson(j, path);
}

void Checksum::Add(std::string_view bytes) {
  std::uint64_t h = h_;
  for (const char c : bytes) {
    h ^= static_cast<unsigned char>(c);
    h *= 1099511628211ull;
  }
  h_ = h;
}

std::string Checksum::Hex() const { return fmt::format("{:016x}", h_); }

std::string FileChecksum(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw DataError(fmt::format("cannot open '{}'", path));
  Checksum checksum;
  char buffer[1 << 16];
  while (in) {
    in.read(buffer, sizeof buffer);
    checksum.Add(std::string_view(buffer, static_cast<std::size_t>(in.gcount())));
  }
  return checksum.Hex();
}

}  // namespace ident::workflow
