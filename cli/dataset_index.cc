#include "cli/dataset_index.h"

#include <cstdlib>
#include <filesystem>
#include <fstream>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <nlohmann/json.hpp>

#include "common/error.h"

#ifndef IDENT_DATASETS_DIR
#define IDENT_DATASETS_DIR "datasets"
#endif

namespace ident::cli {
namespace {

StructureCliOptions ParseStructure(const nlohmann::json& j) {
  StructureCliOptions s;
  s.output = j.at("output").get<std::string>();
  if (j.contains("regressors")) {
    s.regressors = j.at("regressors").get<std::vector<std::string>>();
    s.intercept = j.value("intercept", false);
  } else {
    s.inputs = j.at("input").get<std::vector<std::string>>();
    s.na = j.at("na").get<int>();
    s.nb = j.at("nb").get<std::vector<int>>();
    s.nk = j.at("nk").get<std::vector<int>>();
  }
  return s;
}

}  // namespace

std::string DatasetsDirectory() {
  const char* env = std::getenv("IDENT_DATASETS");
  return env && *env ? std::string(env) : std::string(IDENT_DATASETS_DIR);
}

std::vector<DatasetInfo> LoadDatasetIndex() {
  const std::string dir = DatasetsDirectory();
  const std::string path = dir + "/index.json";
  std::ifstream in(path);
  if (!in)
    throw DataError(
        fmt::format("cannot open the dataset index '{}' (set IDENT_DATASETS to the datasets directory)", path));
  std::vector<DatasetInfo> index;
  try {
    const nlohmann::json j = nlohmann::json::parse(in);
    for (const auto& e : j.at("datasets")) {
      DatasetInfo d;
      d.name = e.at("name").get<std::string>();
      d.file = e.at("file").get<std::string>();
      d.path = dir + "/" + d.file;
      d.system = e.value("system", "");
      if (e.contains("ts") && e["ts"].is_number()) d.ts = e["ts"].get<double>();
      d.structure = ParseStructure(e.at("structure"));
      d.split = e.value("split", 0.5);
      index.push_back(std::move(d));
    }
  } catch (const nlohmann::json::exception& e) {
    throw DataError(fmt::format("{}: malformed dataset index ({})", path, e.what()));
  }
  return index;
}

std::optional<DatasetInfo> FindDataset(const std::string& name) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (!fs::is_regular_file(DatasetsDirectory() + "/index.json", ec)) return std::nullopt;
  for (DatasetInfo& d : LoadDatasetIndex()) {
    if (d.name == name || d.file == name) return d;
    if (fs::exists(name, ec) && fs::equivalent(name, d.path, ec)) return d;
  }
  return std::nullopt;
}

CsvShape ReadCsvShape(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw DataError(fmt::format("cannot open '{}'", path));
  CsvShape shape;
  std::string line;
  std::getline(in, line);
  if (!line.empty() && line.back() == '\r') line.pop_back();
  for (std::size_t start = 0; start <= line.size();) {
    const std::size_t comma = std::min(line.find(',', start), line.size());
    shape.columns.push_back(line.substr(start, comma - start));
    start = comma + 1;
  }
  while (std::getline(in, line))
    if (!line.empty() && line != "\r") ++shape.rows;
  std::error_code ec;
  shape.bytes = std::filesystem::file_size(path, ec);
  return shape;
}

std::string StructureArguments(const StructureCliOptions& s) {
  if (!s.regressors.empty())
    return fmt::format("--output {} --regressors {}{}", s.output, fmt::join(s.regressors, ","),
                       s.intercept ? " --intercept" : "");
  return fmt::format("--output {} --input {} --na {} --nb {} --nk {}", s.output, fmt::join(s.inputs, ","), s.na,
                     fmt::join(s.nb, ","), fmt::join(s.nk, ","));
}

}  // namespace ident::cli
