// Command-line options that choose the model structure: ARX/FIR (--output, --input, --na, --nb, --nk)
// or static regression (--output, --regressors, --intercept). Shared by ident fit and ident compare.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "tools/data_source.h"

namespace ident::tools {

struct StructureCliOptions {
  std::string output;
  std::vector<std::string> inputs;
  int na = 2;
  std::vector<int> nb{2};
  std::vector<int> nk{1};
  std::vector<std::string> regressors;
  bool intercept = false;

  void AddTo(CLI::App& app);
  // Throws InvalidArgument (inconsistent options) or DataError (unknown column).
  std::unique_ptr<DataSource> MakeSource(const std::vector<std::string>& columns, const std::string& source) const;
};

}  // namespace ident::tools
