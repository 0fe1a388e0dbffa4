// Bounded cleaning of recorded outputs before they enter later ARX regressors.
//
// In ARX, z(t) holds −y(t−1) … −y(t−na): a gross outlier in the recorded y(t) poisons the next na
// regressors too (errors in variables), whichever estimator runs. An estimator that flags y(t) as an
// outlier can ask the regressor to store a cleaned value instead. The cleaning is the "robust filter"
// cleaner (Martin & Thomson 1982; Masreliez 1975) with a redescending ψ, and with two guards against
// the failure of naive replacement (a wrong model fed its own predictions until it collapses):
//
//   ê = y − ŷ,  ŷ = Θ̂(t−1)'z(t)                                         one-step prediction error
//   y_c = ŷ + s·ψ(ê/s): a gross error (the only kind cleaned, (4) and (5)) says nothing of y beyond ŷ,  (1)
//   ψ = 0 and y_c = ŷ; with gross = 0 every flagged error is cleaned with the Huber ψ,
//   y_c = ŷ + clip(ê, −c·s, +c·s)
//   y_c ← clamp(y_c, y_min, y_max)      y_min/y_max: range of the measured values stored so far    (2)
//   after max_run consecutive cleaned samples the next measured value is stored as is               (3)
//   during the first warm_up samples (the model is not yet trustworthy) only gross errors are       (4)
//   cleaned, by a model-free screen: the prediction is the last stored value ŷ0 and the scale s_Δ the
//   robust scale (1.4826·median of the nonzero |Δ|; exact zeros of a constant or quantised stretch carry
//   no scale) of the last 16 stored differences; |y − ŷ0| > screen·s_Δ stores ŷ0
//   as in (1)–(3)
//   after warm-up a flagged sample is cleaned only if its error is gross against the robust scale of   (5)
//   the recent prediction errors (every prediction, flagged or not, enters that scale; as s_Δ): the
//   estimator's own scale can sit below the bulk of the errors (model mismatch, a scale still
//   adapting), and cleaning ordinary samples turns the regression into an errors-in-variables one
//
// Storing ŷ rather than the Huber value ŷ ± c·s for a gross error matters: the clipped value leaves an
// error of c·s in the next na regressors, in the direction of the outlier, so the bias grows with the
// rate of outliers whatever their size.
// (1) bounds the change per sample, (2) makes every stored value lie in the range of the recorded
// data whatever the model does (no run-away: |y_c| ≤ max |measured y|), (3) lets a genuine level shift
// or a wrong model reconnect to the measurements within max_run samples. An unflagged sample is
// stored unchanged, so for an estimator that never flags (RLS) the regressors are the ordinary ones.
//
// Example:
//   ident::models::OutputCleaner cleaner({.enabled = true});
//   double stored = cleaner.Clean(y, y_hat, scale, /*flagged=*/nu * beta < 0.2);
#pragma once

#include <algorithm>
#include <string>

namespace ident::models {

struct OutputCleaningOptions {
  bool enabled = false;
  double clip = 2.0;   // c in (1), with gross = 0: the stored value stays within c·s of the prediction
  int max_run = 2;     // (3): at most this many consecutive cleaned samples (>= 1)
  int warm_up = 0;     // (4): samples screened model-free after Reset(); 0 = 10 × num_parameters (ArxRegressor)
  double screen = 10;  // (4): a jump beyond this many robust scales of the stored differences is a gross
                       // error (10: none among the first 400 samples of the bundled dryer, gas_furnace and
                       // glassfurnace records; ≥ 100σ outliers on them are); 0 = no screen
  double gross = 5;    // (5): after warm-up a flagged sample is cleaned only if |y − ŷ| exceeds this many
                       // robust scales of the last 16 prediction errors; 0 = every flagged sample
  // "" if valid, else one line naming the option.
  std::string Validate() const;
};

class OutputCleaner {
 public:
  // Throws InvalidArgument naming the option if `options` is invalid.
  explicit OutputCleaner(const OutputCleaningOptions& options = {});

  // The value to store in later regressors for measured y, prediction ŷ, scale s > 0 and the
  // estimator's verdict. `judged` = false: the estimator gives no verdicts (least squares, which weighs
  // every sample alike): y is stored unchanged, also during warm-up. Non-finite inputs or s <= 0 store y
  // unchanged. O(1), no allocation.
  double Clean(double y, double y_hat, double scale, bool flagged, bool judged = true);
  void Reset();
  // The model is trustworthy from now on (the estimator has made its robust start): the model-free
  // warm-up (4) ends here if it has not already.
  void EndWarmUp() { warm_up_end_ = std::min(warm_up_end_, seen_); }
  // The next Clean() screens model-free (4).
  bool in_warm_up() const { return seen_ < warm_up_end_; }
  // After warm-up: is a prediction error e gross against the recent ones, as (5) judges (gross > 0, and at
  // least 5 errors known)?
  bool IsGross(double e) const;
  // The last stored value was cleaned, but the next sample showed the measured y to be right (an
  // innovation, which the dynamics carry on, not an additive outlier): y is accepted as measured and
  // the sample no longer counts as cleaned.
  void Restore(double y);

  const OutputCleaningOptions& options() const { return options_; }
  long cleaned() const { return cleaned_; }  // samples replaced since Reset() (and not restored)

 private:
  double Accept(double y);
  double Store(double y);          // records y as the last stored value and its difference
  double DifferenceScale() const;  // s_Δ of (4); NaN while fewer than 5 differences are known
  double ErrorScale() const;       // the robust scale of (5); NaN while fewer than 5 errors are known
  static double RingScale(const double* ring, int count);

  static constexpr int kDifferences = 16;

  OutputCleaningOptions options_;
  long seen_ = 0, cleaned_ = 0;
  long warm_up_end_ = 0;  // samples screened model-free: warm_up, or fewer after EndWarmUp()
  int run_ = 0;
  double y_min_ = 0, y_max_ = 0;
  bool have_range_ = false;
  double last_ = 0;                        // the last stored value
  double differences_[kDifferences] = {};  // ring of the last stored differences
  int num_differences_ = 0, next_difference_ = 0;
  double errors_[kDifferences] = {};  // ring of the last prediction errors y − ŷ (after warm-up)
  int num_errors_ = 0, next_error_ = 0;
};

}  // namespace ident::models
