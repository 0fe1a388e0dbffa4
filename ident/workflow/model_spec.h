// The model structure of a fit, as a user states it: ARX/FIR (output, inputs, na, nb, nk), ARMAX/OE/BJ
// (also nc, nd, nf; models/polynomial_structure.h) or static
// regression (output, regressors, intercept), and the cleaning of past outputs in ARX regressors
// (models/output_cleaner.h) with the estimator-side decision that drives it
// (ident/regression/outlier_decision.h). The command line (`--output`, `--input`, `--na`, …) and the
// Python package fill the same fields.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "ident/regression/outlier_decision.h"
#include "ident/workflow/data_source.h"
#include "models/output_cleaner.h"

namespace ident::workflow {

struct ModelSpec {
  std::string output;
  std::vector<std::string> inputs;  // ARX/FIR
  int na = 2;
  std::vector<int> nb{2};  // one value, or one per input
  std::vector<int> nk{1};
  int nc = 0, nd = 0, nf = 0;           // ARMAX (nc), OE (nf, na = 0), Box-Jenkins (nc, nd, nf, na = 0); all 0: ARX
  std::string recursion = "rplr";       // ARMAX/OE/BJ: "rplr" (pseudo-linear regression) or "rpem"
  std::vector<std::string> regressors;  // static regression (excludes inputs)
  bool intercept = false;
  std::string clean_regressors = "on";     // "on" | "off" (on: safe by bench/cleaning_study.py)
  models::OutputCleaningOptions cleaning;  // clip, gross; `enabled` follows clean_regressors
  double clean_below = 0.2;                // flag a sample as outlier when νβ is below this

  // The estimator-side decision that goes with `cleaning`. Throws InvalidArgument if invalid.
  OutlierDecision Decision() const;
  // The data source on a table with these `columns`; `source` names the record in messages.
  // Throws InvalidArgument (inconsistent options) or DataError (unknown column).
  std::unique_ptr<DataSource> MakeSource(const std::vector<std::string>& columns, const std::string& source) const;
  // "none" for a static regression with an intercept (the intercept absorbs the mean), else "mean".
  // True for ARMAX/OE/BJ (any of nc, nd, nf above 0).
  bool polynomial() const { return nc > 0 || nd > 0 || nf > 0; }
  std::string DefaultDetrend() const { return intercept ? "none" : "mean"; }
};

}  // namespace ident::workflow
