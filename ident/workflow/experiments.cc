#include "ident/workflow/experiments.h"

#include <cmath>
#include <utility>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "common/error.h"

namespace ident::workflow {

std::vector<Experiment> WholeRecord(const io::DataTable& table, const std::string& name) {
  return {Experiment{.name = name, .first = 0, .count = table.num_rows()}};
}

std::vector<Experiment> LabelExperiments(io::DataTable& table, const std::string& column) {
  const int c = table.ColumnIndex(column);
  std::vector<Experiment> experiments;
  table.experiment_starts.clear();
  for (int r = 0; r < table.num_rows(); ++r) {
    const double label = table.values(r, c);
    if (std::isnan(label))
      throw DataError(
          fmt::format("{}: data row {}: the experiment column '{}' is missing", table.source, r + 1, column));
    if (r == 0 || label != table.values(r - 1, c)) {
      if (r > 0) table.experiment_starts.push_back(r);
      experiments.push_back({.name = fmt::format("{:g}", label), .first = r, .count = 0});
    }
    ++experiments.back().count;
  }
  return experiments;
}

io::DataTable ConcatenateExperiments(std::vector<io::DataTable> tables, const std::string& column,
                                     std::vector<Experiment>* experiments) {
  IDENT_REQUIRE(!tables.empty(), "no data file given");
  io::DataTable all;
  all.names = tables.front().names;
  long rows = 0;
  std::vector<std::string> sources;
  for (const io::DataTable& t : tables) {
    if (t.names != all.names)
      throw DataError(fmt::format("{}: columns ({}) differ from {}'s ({}); every experiment needs the same columns",
                                  t.source, fmt::join(t.names, ", "), tables.front().source,
                                  fmt::join(all.names, ", ")));
    rows += t.num_rows();
    sources.push_back(t.source);
  }
  all.source = fmt::format("{}", fmt::join(sources, " + "));
  all.values.resize(rows, static_cast<Eigen::Index>(all.names.size()));
  std::vector<Experiment> list;
  int first = 0;
  for (io::DataTable& t : tables) {
    std::vector<Experiment> parts = WholeRecord(t, t.source);
    if (!column.empty()) {
      parts = LabelExperiments(t, column);
      if (tables.size() > 1)
        for (Experiment& e : parts) e.name = t.source + ":" + e.name;
    }
    for (Experiment& e : parts) {
      e.first += first;
      if (e.first > 0) all.experiment_starts.push_back(e.first);
      list.push_back(std::move(e));
    }
    all.values.middleRows(first, t.num_rows()) = t.values;
    first += t.num_rows();
  }
  if (experiments) *experiments = std::move(list);
  return all;
}

std::vector<Experiment> TableExperiments(const io::DataTable& table) {
  std::vector<Experiment> experiments = WholeRecord(table, "1");
  for (std::size_t i = 0; i < table.experiment_starts.size(); ++i) {
    const int start = table.experiment_starts[i];
    experiments.back().count = start - experiments.back().first;
    experiments.push_back({.name = std::to_string(i + 2), .first = start, .count = table.num_rows() - start});
  }
  return experiments;
}

nlohmann::ordered_json ExperimentsJson(const std::vector<Experiment>& experiments) {
  nlohmann::ordered_json list = nlohmann::ordered_json::array();
  for (const Experiment& e : experiments)
    list.push_back({{"name", e.name}, {"rows", {e.first + 1, e.first + e.count}}});
  return list;
}

}  // namespace ident::workflow
