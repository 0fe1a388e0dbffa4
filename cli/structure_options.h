// Command-line options that choose the model structure: ARX/FIR (--output, --input, --na, --nb, --nk),
// ARMAX/OE/Box-Jenkins (also --nc, --nd, --nf) or static regression (--output, --regressors, --intercept). Shared by ident fit and ident compare.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "ident/workflow/model_spec.h"

namespace ident::cli {

// The fields and their meaning are workflow::ModelSpec's; this adds the command line.
struct StructureCliOptions : workflow::ModelSpec {
  // Adds the options to `app`. `require_output` = false lets a command fill the structure from a
  // dataset's suggestion (ident compare) when no structure option is given.
  void AddTo(CLI::App& app, bool require_output = true);
  // True if the user gave any structure option on the command line (after parsing).
  bool Given() const;
  // This structure with every option the user did not give taken from `suggestion` (a dataset's
  // suggested structure): output; inputs/regressors unless either was given; orders per option
  // (nb/nk only if they fit the number of inputs).
  StructureCliOptions WithDefaultsFrom(const StructureCliOptions& suggestion) const;

 private:
  std::vector<const CLI::Option*> options_;  // set by AddTo, read by Given()
};

}  // namespace ident::cli
