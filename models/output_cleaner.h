// Bounded cleaning of recorded outputs before they enter later ARX regressors.
//
// In ARX, z(t) holds −y(t−1) … −y(t−na): a gross outlier in the recorded y(t) poisons the next na
// regressors too (errors in variables), whichever estimator runs. An estimator that flags y(t) as an
// outlier can ask the regressor to store a cleaned value instead. The cleaning is the Huber-ψ
// "robust filter" cleaner (Martin & Thomson 1982; Masreliez 1975), with two guards against the
// failure of naive replacement (a wrong model fed its own predictions until it collapses):
//
//   ê = y − ŷ,  ŷ = Θ̂(t−1)'z(t)                                         one-step prediction error
//   y_c = ŷ + clip(ê, −c·s, +c·s)                     Huber ψ: keeps the sign and c·s of the error  (1)
//   y_c ← clamp(y_c, y_min, y_max)      y_min/y_max: range of the measured values stored so far    (2)
//   after max_run consecutive cleaned samples the next measured value is stored as is               (3)
//   no cleaning during the first warm_up samples (the model is not yet trustworthy)                 (4)
//
// (1) bounds the change per sample, (2) makes every stored value lie in the range of the recorded
// data whatever the model does (no run-away: |y_c| ≤ max |measured y|), (3) lets a genuine level shift
// or a wrong model reconnect to the measurements within max_run samples. An unflagged sample is
// stored unchanged, so for an estimator that never flags (RLS) the regressors are the ordinary ones.
//
// Example:
//   ident::models::OutputCleaner cleaner({.enabled = true});
//   double stored = cleaner.Clean(y, y_hat, scale, /*flagged=*/nu * beta < 0.2);
#pragma once

#include <string>

namespace ident::models {

struct OutputCleaningOptions {
  bool enabled = false;
  double clip = 2.0;  // c in (1): the stored value stays within c·s of the prediction
  int max_run = 2;    // (3): at most this many consecutive cleaned samples (>= 1)
  int warm_up = 0;    // (4): samples stored unchanged after Reset(); 0 = 10 × num_parameters (ArxRegressor)
  // "" if valid, else one line naming the option.
  std::string Validate() const;
};

class OutputCleaner {
 public:
  // Throws InvalidArgument naming the option if `options` is invalid.
  explicit OutputCleaner(const OutputCleaningOptions& options = {});

  // The value to store in later regressors for measured y, prediction ŷ, scale s > 0 and the
  // estimator's verdict. Non-finite inputs or s <= 0 store y unchanged. O(1), no allocation.
  double Clean(double y, double y_hat, double scale, bool flagged);
  void Reset();

  const OutputCleaningOptions& options() const { return options_; }
  long cleaned() const { return cleaned_; }  // samples replaced since Reset()

 private:
  double Accept(double y);

  OutputCleaningOptions options_;
  long seen_ = 0, cleaned_ = 0;
  int run_ = 0;
  double y_min_ = 0, y_max_ = 0;
  bool have_range_ = false;
};

}  // namespace ident::models
