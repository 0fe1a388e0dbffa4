// ARX model structure and its regressor, built sample by sample from a stream.
//
//   y(t) + a1 y(t−1) + … + a_na y(t−na) = Σ_i [b_i1 u_i(t−nk_i) + … + b_i,nb_i u_i(t−nk_i−nb_i+1)] + e(t)
//   θ = [a1 … a_na, b_11 … b_1,nb_1, b_21 …]      (the b-block of input 1, then input 2, …)
//   z(t) = [−y(t−1) … −y(t−na), u_1(t−nk_1) … u_1(t−nk_1−nb_1+1), u_2(t−nk_2) …],  y(t) = θ'z(t) + e(t)
//
// The first regression index inside a segment (0-based) is t0 = max(na, max_i(nk_i + nb_i − 1)):
// the first sample whose regressor needs no data from before the segment. FIR: na = 0.
//
// Example (ARX(2,2,3), one input):
//   ident::models::ArxStructure arx(2, {2}, {3});
//   ident::models::ArxRegressor reg(arx);
//   for (t...) { if (reg.Next(u.row(t), z)) est.Update(y(t), z); reg.PushOutput(y(t)); }
#pragma once

#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "models/output_cleaner.h"

namespace ident::models {

class ArxStructure {
 public:
  // Limits that keep the memory a recursive estimator needs sane: at most kMaxParameters parameters (its
  // (ρ+1)×(ρ+1) information matrix alone is 800 MB at ρ = 10⁴) and input histories nk_i + nb_i of at most
  // kMaxHistory samples (one buffer of doubles per input).
  static constexpr int kMaxParameters = 10'000;
  static constexpr int kMaxHistory = 10'000'000;

  // Throws InvalidArgument if na < 0, an nb_i < 0, an nk_i < 0, the sizes of nb and nk differ,
  // there are no parameters, or a limit above is exceeded.
  ArxStructure(int na, std::vector<int> nb, std::vector<int> nk);

  int na() const { return na_; }
  const std::vector<int>& nb() const { return nb_; }
  const std::vector<int>& nk() const { return nk_; }
  int num_inputs() const { return static_cast<int>(nb_.size()); }
  int num_parameters() const { return num_parameters_; }
  // t0 = max(na, max_i(nk_i + nb_i − 1)), at least 0.
  int first_regression_index() const { return t0_; }
  // Input history needed per input: nk_i + nb_i samples (u(t−nk−nb+1) … u(t)).
  int input_history(int i) const { return nk_[i] + nb_[i]; }
  // "ARX(2,2,3)" or "ARX(2,[2,2],[1,1])"; "FIR(…)" for na = 0.
  std::string ToString() const;
  // Names of θ's entries: a1…a_na, b1…b_nb (one input) or b1_1… (several inputs).
  std::vector<std::string> ParameterNames() const;

 private:
  int na_;
  std::vector<int> nb_, nk_;
  int num_parameters_ = 0;
  int t0_ = 0;
};

// Forms z(t) from a stream of samples. Per sample t: Next(u(t), z) stores u(t) and, if t ≥ t0,
// writes z(t) and returns true; then PushOutput(y(t)) stores the output (measured, or simulated
// for simulation). No allocation after construction.
//
// Outlier cleaning (models/output_cleaner.h): with `cleaning.enabled`, PushCheckedOutput(y, ŷ, s,
// flagged) stores the bounded cleaned value instead of y when the estimator flagged the sample.
class ArxRegressor {
 public:
  explicit ArxRegressor(const ArxStructure& structure, const OutputCleaningOptions& cleaning = {});

  void Reset();
  // u has one entry per input.
  bool Next(const Eigen::Ref<const Eigen::VectorXd>& u, Eigen::Ref<Eigen::VectorXd> z);
  void PushOutput(double y);
  // Stores the measured y, or its cleaned value if cleaning is on and `flagged` (prediction ŷ = Θ̂'z(t),
  // scale s = the estimator's noise scale). Returns the stored value.
  double PushCheckedOutput(double y, double y_hat, double scale, bool flagged, bool judged = true);
  // Additive outlier or innovation? After Next() has formed z(t), if y(t−1) was cleaned: writes z(t)
  // with the measured y(t−1) instead into z_measured and returns true (else false). The caller compares
  // how well each predicts y(t) — an additive outlier leaves y(t) consistent with the cleaned value, an
  // innovation outlier (carried on by the dynamics) with the measured one — and, for the measured,
  // calls RestoreMeasured(), which puts the measured y(t−1) back for every later regressor.
  bool MeasuredRegressor(Eigen::Ref<Eigen::VectorXd> z_measured) const;
  void RestoreMeasured();
  // Whether a prediction error of y(t) is gross for the cleaner ((5) of models/output_cleaner.h): a reading
  // under which y(t) is itself a gross error explains nothing (two outliers in a row look like an
  // innovation followed by its echo).
  bool IsGrossError(double e) const { return !cleaner_.in_warm_up() && cleaner_.IsGross(e); }
  // The same question while no model judges (y(t−1) was cleaned by the warm-up's model-free screen, (4)
  // of models/output_cleaner.h): the screen's own predictor, the last stored value, answers it — true if
  // y(t) lies nearer the measured y(t−1) than the cleaned one. nullopt when y(t−1) was not cleaned so.
  std::optional<bool> MeasuredIsNearer(double y) const;
  // The regressor Next() formed holds a cleaned output (one of y(t−1) … y(t−na) is stored cleaned): its
  // equation is an errors-in-variables one, which the workflow leaves out as if the output were missing.
  bool HoldsCleaned() const { return cleaned_in_window_ > 0; }
  // The estimator's predictions are trustworthy from now on: ends the cleaner's model-free warm-up.
  void EndCleaningWarmUp() { cleaner_.EndWarmUp(); }
  const ArxStructure& structure() const { return structure_; }
  const OutputCleaner& cleaner() const { return cleaner_; }

 private:
  // z from the stored windows: −y(t−1) … −y(t−na), then each input's u_i(t−nk_i) … u_i(t−nk_i−nb_i+1).
  void FillRegressor(Eigen::Ref<Eigen::VectorXd> z) const;

  ArxStructure structure_;
  Eigen::VectorXd past_y_;          // past_y_(k) = y(t−1−k), k < na (as stored: maybe cleaned)
  double last_measured_ = 0;        // the measured y(t−1)
  bool last_cleaned_ = false;       // past_y_(0) is a cleaned value
  bool last_screened_ = false;      // ... cleaned by the model-free warm-up screen
  std::vector<char> past_cleaned_;  // past_cleaned_[k]: past_y_(k) is a cleaned value
  int cleaned_in_window_ = 0;       // how many of past_cleaned_ are set
  // The inputs' windows one after another in one array, input i's from u_window_[i] on:
  // past_u_[u_window_[i] + k] = u_i(t−k), k < nk_i + nb_i. Next() moves them all on in one shift.
  std::vector<double> past_u_;
  std::vector<std::pair<int, int>> u_heads_;  // (i, u_window_[i]) of the inputs with a window
  std::vector<int> z_from_u_;                 // z(na + j) = past_u_[z_from_u_[j]]
  long samples_ = 0;                          // samples pushed with Next()
  long outputs_ = 0;
  OutputCleaner cleaner_;
};

// Static linear regression y = θ'x + e with an optional intercept (first entry of θ).
struct StaticRegression {
  std::vector<std::string> regressors;
  bool intercept = false;
  int num_parameters() const { return static_cast<int>(regressors.size()) + (intercept ? 1 : 0); }
  std::vector<std::string> ParameterNames() const;
  // z = [1, x] or x.
  void Regressor(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> z) const;
};

}  // namespace ident::models
