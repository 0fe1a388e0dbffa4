// Several experiments in one fit (`ident fit A.csv B.csv`, `--experiment-column`): the records of the
// experiments one after another in one table, with io::DataTable::experiment_starts marking where each
// further experiment begins. The walkers of ident/workflow restart the regressor history there
// (DataSource::Restart), so no regressor straddles two experiments: the first t0 rows of each experiment
// only fill the regressors, as the first rows of a record do.
#pragma once

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "ident/io/csv.h"

namespace ident::workflow {

struct Experiment {
  std::string name;  // the label, the file, or "file:label"
  int first = 0;     // 0-based first row in the table
  int count = 0;
};

// The whole table as one experiment named `name`.
std::vector<Experiment> WholeRecord(const io::DataTable& table, const std::string& name);

// Splits the table at every change of the value of `column` (consecutive rows with the same value are
// one experiment; a label that comes back later starts a new one), sets table.experiment_starts and
// returns the experiments, named by their label ("3", "0.5"). Throws DataError for an unknown column or a
// missing (NaN) label, naming the row.
std::vector<Experiment> LabelExperiments(io::DataTable& table, const std::string& column);

// The tables one after another, each a separate experiment (split further by `column` if not empty, as
// LabelExperiments does; names then "file:label", or the label alone for one file). `experiments` receives them. Throws DataError naming the
// file whose columns differ from the first file's, InvalidArgument for an empty list.
io::DataTable ConcatenateExperiments(std::vector<io::DataTable> tables, const std::string& column,
                                     std::vector<Experiment>* experiments);

// The experiments io::DataTable::experiment_starts marks, named "1", "2", … (the whole table as "1" when it
// has none).
std::vector<Experiment> TableExperiments(const io::DataTable& table);

// The JSON list of the reports' `experiments` key: [{name, rows: [first, last]}], 1-based rows.
nlohmann::ordered_json ExperimentsJson(const std::vector<Experiment>& experiments);

}  // namespace ident::workflow
