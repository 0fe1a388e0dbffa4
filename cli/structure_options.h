// Command-line options that choose the model structure: ARX/FIR (--output, --input, --na, --nb, --nk)
// or static regression (--output, --regressors, --intercept). Shared by ident fit and ident compare.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "ident/regression/outlier_decision.h"
#include "ident/workflow/data_source.h"
#include "models/output_cleaner.h"

namespace ident::cli {

struct StructureCliOptions {
  std::string output;
  std::vector<std::string> inputs;
  int na = 2;
  std::vector<int> nb{2};
  std::vector<int> nk{1};
  std::vector<std::string> regressors;
  bool intercept = false;
  // Outlier cleaning of past outputs in ARX regressors (models/output_cleaner.h) and the decision
  // threshold on the estimator's relative weight νβ (ident/regression/outlier_decision.h).
  std::string clean_regressors = "on";     // "on" | "off" (on: safe by bench/cleaning_study.py)
  models::OutputCleaningOptions cleaning;  // clip etc.; `enabled` follows clean_regressors
  double clean_below = 0.2;

  // Adds the options to `app`. `require_output` = false lets a command fill the structure from a
  // dataset's suggestion (ident compare) when no structure option is given.
  void AddTo(CLI::App& app, bool require_output = true);
  // True if the user gave any structure option on the command line (after parsing).
  bool Given() const;
  // This structure with every option the user did not give taken from `suggestion` (a dataset's
  // suggested structure): output; inputs/regressors unless either was given; orders per option
  // (nb/nk only if they fit the number of inputs).
  StructureCliOptions WithDefaultsFrom(const StructureCliOptions& suggestion) const;
  // The estimator-side decision that goes with `cleaning`. Throws InvalidArgument if invalid.
  OutlierDecision Decision() const;
  // Throws InvalidArgument (inconsistent options) or DataError (unknown column).
  std::unique_ptr<workflow::DataSource> MakeSource(const std::vector<std::string>& columns,
                                                   const std::string& source) const;

 private:
  std::vector<const CLI::Option*> options_;  // set by AddTo, read by Given()
};

}  // namespace ident::cli
