#include "cli/structure_options.h"

namespace ident::cli {

void StructureCliOptions::AddTo(CLI::App& app, bool require_output) {
  auto* output_option = app.add_option("--output", output, "Output column y (one output at a time for MIMO data)")
                            ->required(require_output);
  auto* input =
      app.add_option("--input", inputs, "Input column(s) u (comma-separated for several inputs)")->delimiter(',');
  auto* na_option = app.add_option("--na", na, "ARX order of the output polynomial (0: FIR)")->capture_default_str();
  auto* nb_option = app.add_option("--nb", nb, "Number of b coefficients (one value, or one per input)")
                        ->delimiter(',')
                        ->capture_default_str();
  auto* nk_option = app.add_option("--nk", nk, "Input delay in samples (one value, or one per input)")
                        ->delimiter(',')
                        ->capture_default_str();
  app.add_option("--nc", nc, "ARMAX/Box-Jenkins: order of the noise numerator C (0: none)")->capture_default_str();
  app.add_option("--nd", nd, "Box-Jenkins: order of the noise denominator D (needs --nf)")->capture_default_str();
  app.add_option("--nf", nf, "OE/Box-Jenkins: order of the input denominator F (one input; without --na, na = 0)")
      ->capture_default_str()
      ->each([this, na_option](const std::string&) {
        if (na_option->count() == 0) na = 0;
      });
  app.add_option("--recursion", recursion,
                 "ARMAX/OE/BJ: rplr (pseudo-linear regression) or rpem (prediction-error method: the gradient "
                 "filtered by 1/C, 1/F or D/(CF))")
      ->check(CLI::IsMember({"rplr", "rpem"}))
      ->capture_default_str();
  auto* regressors_option =
      app.add_option("--regressors", regressors, "Static regression on these columns (comma-separated)")
          ->delimiter(',')
          ->excludes(input)
          ->excludes(na_option)
          ->excludes(nb_option)
          ->excludes(nk_option);
  auto* intercept_option =
      app.add_flag("--intercept", intercept, "Static regression: add an intercept (first parameter)")
          ->needs(regressors_option);
  app.add_option("--clean-regressors", clean_regressors,
                 "ARX (and the A part of ARMAX/BJ): an output the estimator flags as an outlier (nu*beta < "
                 "--clean-below) is stored cleaned, and the equations whose regressors hold it are left out")
      ->check(CLI::IsMember({"on", "off"}))
      ->capture_default_str();
  app.add_option("--clean-clip", cleaning.clip,
                 "With --clean-gross 0: a flagged output is stored as the prediction plus its error clipped to C "
                 "noise scales (Huber)")
      ->capture_default_str();
  app.add_option("--clean-gross", cleaning.gross,
                 "Clean a flagged output only if its error exceeds G robust scales of the recent prediction errors, "
                 "and then store the prediction; 0: clean every flagged output with --clean-clip")
      ->capture_default_str();
  app.add_option("--clean-below", clean_below, "Flag a sample as outlier when its relative weight nu*beta is below W")
      ->capture_default_str();
  options_ = {output_option, input, na_option, nb_option, nk_option, regressors_option, intercept_option};
}

bool StructureCliOptions::Given() const {
  for (const CLI::Option* option : options_)
    if (option->count() > 0) return true;
  return false;
}

StructureCliOptions StructureCliOptions::WithDefaultsFrom(const StructureCliOptions& suggestion) const {
  enum { kOutput, kInput, kNa, kNb, kNk, kRegressors, kIntercept };
  auto given = [this](std::size_t i) { return i < options_.size() && options_[i]->count() > 0; };
  StructureCliOptions r = *this;
  if (!given(kOutput)) r.output = suggestion.output;
  if (given(kRegressors)) return r;
  if (!given(kInput) && !given(kIntercept)) {
    r.inputs = suggestion.inputs;
    r.regressors = suggestion.regressors;
    r.intercept = suggestion.intercept;
  }
  if (!r.regressors.empty()) return r;
  const bool same_inputs = r.inputs.size() == suggestion.inputs.size();
  if (!given(kNa)) r.na = r.nf > 0 ? 0 : suggestion.na;  // OE/BJ: no A polynomial
  if (!given(kNb) && same_inputs) r.nb = suggestion.nb;
  if (!given(kNk) && same_inputs) r.nk = suggestion.nk;
  return r;
}

}  // namespace ident::cli
