#include "cli/experiment_records.h"

#include <utility>

#include <fmt/format.h>

#include "common/error.h"
#include "ident/io/mat_file.h"

namespace ident::cli {

void AddExperimentColumnOption(CLI::App& app, std::string& column) {
  app.add_option("--experiment-column", column,
                 "Column labelling the experiment: each run of one label is an experiment, and the regressors "
                 "restart at each");
}

void AddDataFilesOptions(CLI::App& app, std::vector<std::string>& data, std::string& experiment_column,
                         const std::string& what) {
  app.add_option("DATA", data, what + "; several: one experiment each")->required();
  AddExperimentColumnOption(app, experiment_column);
}

void AddMissingOption(CLI::App& app, bool& missing) {
  app.add_flag("--missing", missing,
               "Treat empty/NaN/Inf cells as missing samples instead of errors; fill gaps of the time column t "
               "with missing samples");
}

void PrintExperiments(const std::vector<workflow::Experiment>& experiments) {
  if (experiments.size() <= 1) return;
  fmt::print("{} experiments (regressors restart at each):", experiments.size());
  for (std::size_t i = 0; i < experiments.size(); ++i)
    fmt::print("{} {} rows {}-{}", i ? "," : "", experiments[i].name, experiments[i].first + 1,
               experiments[i].first + experiments[i].count);
}

ExperimentRecords ReadExperimentRecords(const std::vector<std::string>& paths, const std::string& column,
                                        const io::CsvOptions& csv) {
  IDENT_REQUIRE(!paths.empty(), "no data file given");
  ExperimentRecords r;
  r.several = paths.size() > 1 || !column.empty();
  std::vector<io::DataTable> tables;
  for (const std::string& p : paths) {
    tables.push_back(io::ReadDataFile(p, csv));
    r.files.push_back({p, tables.back().num_rows(), ""});
  }
  if (r.several) {
    r.table = workflow::ConcatenateExperiments(std::move(tables), column, &r.experiments);
  } else {
    r.table = std::move(tables.front());
    r.experiments = workflow::TableExperiments(r.table);
  }
  r.name = r.several ? r.table.source : paths.front();
  return r;
}

}  // namespace ident::cli
