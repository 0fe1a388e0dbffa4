// The index of the bundled datasets (datasets/index.json): name, file, system, sampling time and
// the suggested model structure of each record, plus cheap facts read from the file itself.
//
// Example:
//   for (const DatasetInfo& d : ident::cli::LoadDatasetIndex()) fmt::print("{} {}\n", d.name, d.file);
//   std::optional<DatasetInfo> dryer = ident::cli::FindDataset("dryer");   // nullopt if not bundled
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "cli/structure_options.h"

namespace ident::cli {

struct DatasetInfo {
  std::string name;               // bare name accepted wherever a data file is ("dryer")
  std::string file;               // file name inside the datasets directory
  std::string path;               // datasets directory + file
  std::string system;             // one-line description
  std::optional<double> ts;       // sampling time [s], if the source gives one
  StructureCliOptions structure;  // suggested structure (the defaults of `ident compare NAME`)
  double split = 0.5;             // estimation fraction used by the README baselines
};

// The datasets directory: $IDENT_DATASETS if set, else the source tree's datasets/.
std::string DatasetsDirectory();

// Reads <DatasetsDirectory()>/index.json. Throws DataError naming the file if it is missing or malformed.
std::vector<DatasetInfo> LoadDatasetIndex();

// The entry whose name equals `name`, or whose path/file name is `name` (a path into the datasets
// directory also matches); nullopt otherwise (also when there is no index).
std::optional<DatasetInfo> FindDataset(const std::string& name);

// Shape of a CSV file read cheaply: header columns and number of data rows (non-empty lines after
// the header). Throws DataError if the file cannot be opened.
struct CsvShape {
  std::vector<std::string> columns;
  long rows = 0;
  std::uintmax_t bytes = 0;
};
CsvShape ReadCsvShape(const std::string& path);

// "--output y --input u --na 2 --nb 2 --nk 3" for a structure.
std::string StructureArguments(const StructureCliOptions& s);

}  // namespace ident::cli
