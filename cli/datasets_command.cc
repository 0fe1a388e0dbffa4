// ident datasets [--json]: the bundled records with rows, columns, size and suggested structure.
#include <iostream>
#include <memory>
#include <vector>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <nlohmann/json.hpp>

#include "cli/commands.h"
#include "cli/dataset_index.h"

namespace ident::cli {
namespace {

std::string HumanSize(std::uintmax_t bytes) {
  if (bytes >= 1000 * 1000) return fmt::format("{:.1f} MB", static_cast<double>(bytes) / 1e6);
  if (bytes >= 1000) return fmt::format("{:.0f} kB", static_cast<double>(bytes) / 1e3);
  return fmt::format("{} B", bytes);
}

void RunDatasets(bool json) {
  const std::vector<DatasetInfo> index = LoadDatasetIndex();
  // Every file is read before anything is printed: a missing one is one error line, no partial table.
  std::vector<CsvShape> shapes;
  for (const DatasetInfo& d : index) shapes.push_back(ReadCsvShape(d.path));
  nlohmann::ordered_json list = nlohmann::ordered_json::array();
  if (!json) fmt::print("{:<26} {:>7} {:>8}  {:<44} {}\n", "name", "rows", "size", "columns", "suggested structure");
  for (std::size_t i = 0; i < index.size(); ++i) {
    const DatasetInfo& d = index[i];
    const CsvShape& shape = shapes[i];
    const std::string args = StructureArguments(d.structure);
    if (json) {
      nlohmann::ordered_json e;
      e["name"] = d.name;
      e["file"] = d.path;
      e["system"] = d.system;
      e["ts"] = d.ts ? nlohmann::ordered_json(*d.ts) : nlohmann::ordered_json();
      e["rows"] = shape.rows;
      e["columns"] = shape.columns;
      e["bytes"] = shape.bytes;
      e["structure"] = args;
      e["split"] = d.split;
      list.push_back(std::move(e));
    } else {
      fmt::print("{:<26} {:>7} {:>8}  {:<44} {}\n", d.name, shape.rows, HumanSize(shape.bytes),
                 fmt::format("{}", fmt::join(shape.columns, ",")), args);
    }
  }
  if (json)
    std::cout << list.dump(2) << "\n";
  else
    fmt::print(
        "\nUse a name wherever a data file goes, e.g. `ident fit dryer --output y --input u --nk 3`;\n"
        "`ident compare NAME` uses the suggested structure. Provenance: {}/README.md\n",
        DatasetsDirectory());
}

}  // namespace

void AddDatasetsCommand(CLI::App& app) {
  auto json = std::make_shared<bool>(false);
  CLI::App* cmd = app.add_subcommand("datasets", "List the bundled datasets: rows, columns, size, suggested structure");
  cmd->add_flag("--json", *json, "Print a JSON array instead of the table");
  cmd->callback([json] { RunDatasets(*json); });
}

}  // namespace ident::cli
