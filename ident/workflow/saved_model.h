// A fitted model that leaves the program: `ident fit --save model.json` writes it, `ident predict` reads
// it back and predicts or simulates on any record with the same columns, in physical units.
//
// model.json (format "ident-model", version 1):
//   structure        {"kind": "arx", "output", "inputs", "na", "nb", "nk"},
//                    {"kind": "armax" | "oe" | "bj", the same and "nc", "nd", "nf"} or
//                    {"kind": "static", "output", "regressors", "intercept"}
//   structure_name, parameter_names, theta, covariance (ρ×ρ), theta_std, noise_std
//   detrend          "mean" or "none"; detrend_means {column: mean subtracted before fitting}
//   estimator        {"name", "kind", "passes"}
//   data             {"path", "rows", "fnv1a64": checksum of the file's bytes, 16 hex digits ("" when the
//                    record came from standard input or a pipe, or from several files), "files": [{"path",
//                    "rows", "fnv1a64"}] one per file read (several: one per experiment file)}
//   split, validation_rows [first, last] (1-based), fit_percent and rms of the fit's validation
// Numbers carry 17 significant digits, so θ and the means read back bit for bit.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "ident/workflow/fit.h"
#include "ident/workflow/model_spec.h"

namespace ident::workflow {

struct SavedModel {
  ModelSpec model;
  std::string structure_name;
  std::vector<std::string> parameter_names;
  Eigen::VectorXd theta, theta_std;
  Eigen::MatrixXd covariance;
  double noise_std = 0;
  std::string detrend = "mean";
  std::vector<std::pair<std::string, double>> detrend_means;  // column name, mean
  std::string estimator, kind;
  int passes = 1;
  std::string data_path, data_checksum;
  long data_rows = 0;
  struct DataFile {
    std::string path, checksum;  // checksum "" for standard input or a pipe
    long rows = 0;
  };
  std::vector<DataFile> data_files;  // every file read, in order (empty in a model file without "files")
  double split = 0.5;
  Segment validation;  // 0-based rows of the fit's validation part
  FitScores validation_scores;

  nlohmann::ordered_json ToJson() const;
  // Throws DataError naming `source` and the key for a file that is not such a model.
  static SavedModel FromJson(const nlohmann::json& j, const std::string& source);
  static SavedModel Read(const std::string& path);
};

// FNV-1a, 64 bits, of bytes given in order, as 16 hex digits (FileChecksum, or a file's bytes as they are read:
// io::CsvOptions::on_bytes).
class Checksum {
 public:
  void Add(std::string_view bytes);
  std::string Hex() const;

 private:
  std::uint64_t h_ = 14695981039346656037ull;
};

// Checksum of a file's bytes. Throws DataError if it cannot be read.
std::string FileChecksum(const std::string& path);

}  // namespace ident::workflow
