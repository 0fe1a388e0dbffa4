// The pseudo-linear regressor φ(t) of an ARMAX/OE/BJ model (models/polynomial_structure.h), built
// sample by sample from a stream, as recursive pseudo-linear regression (RPLR, also called recursive
// extended least squares; Ljung, System Identification, 2nd ed., §11.5 and eq. (10.52); Ljung &
// Söderström, Theory and Practice of Recursive Identification, 1983, §3.7) needs it:
//
//   φ(t) = [−y(t−1)…, u(t−nk)…, ε(t−1)…, −v(t−1)…, −w(t−1)…]
//   after y(t):  ŷ(t) = θ'φ(t),  ε(t) = y(t) − ŷ(t)                        (a-posteriori residual)
//                w(t) = θ_b'φ_b(t) + θ_f'φ_f(t)                            (noise-free output B/F u)
//                v(t) = y(t) − θ_a'φ_a(t) − w(t)                            (noise A y − w)
//
// with θ the estimate the caller last gave: during recursive estimation TrackEstimate(θ(t)) after the
// update at t (so ε is the a-posteriori residual of RELS), for prediction with a fixed model SetEstimate(θ)
// once (a fixed θ also serves a pass of batch extended least squares, whose regressors come from the
// previous pass's estimate). Then θ'φ(t) is the model's one-step prediction (its own past prediction errors in the C part);
// pushing ŷ(t) itself as the output gives ε = 0 and simulates the model from u alone.
//
// Stability projection (Ljung §11.5, the projection into D_M): TrackEstimate keeps the last estimate whose
// C and F polynomials are stable (every root strictly inside the unit circle), since ε = (D/C) v and
// w = (B/F) u are computed by filtering with 1/C and 1/F. Before any estimate is given, the measured y
// stands in for w, ε and v: the regressors' mean squares (a data-scaled prior) then have the data's scale.
// Rows before t0 (no regressor) store w = y, ε = v = 0.
//
// Recursive prediction-error method (RPEM; Ljung & Söderström 1983, §3.7, the Gauss–Newton RPEM of
// eq. (3.130); Ljung §11.4): with `Recursion::kPredictionError`, while an estimate is tracked after the
// warm-up (during it, with w = y, the noise model has no data to be differentiated on: z = φ), Next() writes
// the predictor's gradient ψ(t) = φ(t)/C(q) (ARMAX) or φ(t)/F(q) (OE) — for Box–Jenkins D(q)φ(t)/(C(q)F(q))
// in the B and F coordinates and φ(t)/C(q) in the C and D ones — filtered with the tracked (stable)
// estimate, instead of φ(t), and the estimator regresses the linearised output
// ỹ(t) = y(t) − θ'φ(t) + θ'ψ(t) (LinearisedOutput) on it: its update θ(t) = θ(t−1) + P(t)ψ(t)ε(t),
// ε = y − θ(t−1)'φ, is then the RPEM step with the estimator's own weight (RLS, Cauchy, Student-t).
// A fixed model (SetEstimate) predicts with φ as in RPLR.
//
// Outlier cleaning of y as in models/arx.h (PushCheckedOutput): the cleaned value is used for y and the
// residuals derived from it, and HoldsCleaned() tells the workflow to leave out an equation whose A part
// holds one. No allocation after construction.
#pragma once

#include <Eigen/Core>

#include "models/arx.h"
#include "models/output_cleaner.h"
#include "models/polynomial_structure.h"

namespace ident::models {

enum class Recursion { kPseudoLinear, kPredictionError };

class PseudoLinearRegressor {
 public:
  // Warm-up: the first kWarmUp·ρ tracked estimates keep w = y (an ARX start, the usual initialisation of
  // an OE fit): the noise-free outputs of estimates from a few samples would start the recursion far off.
  static constexpr int kWarmUp = 10;
  explicit PseudoLinearRegressor(const PolynomialStructure& structure, const OutputCleaningOptions& cleaning = {},
                                 Recursion recursion = Recursion::kPseudoLinear);

  // Clears the histories (segment start); keeps the estimate.
  void Reset();
  // As ArxRegressor::Next: stores u(t) and, from t0 on, writes φ(t) and returns true.
  bool Next(const Eigen::Ref<const Eigen::VectorXd>& u, Eigen::Ref<Eigen::VectorXd> z);
  // A fixed model θ (ρ entries), used as given; TrackEstimate leaves it until ClearEstimate().
  void SetEstimate(const Eigen::Ref<const Eigen::VectorXd>& theta);
  // The current recursive estimate: used if its C and F are stable (or no estimate is held yet); else the
  // last one kept stays. Returns true if θ was taken. `measured_noise_free`: the measured (or cleaned) y
  // is stored as the noise-free output w (as in ARX) until an estimate without it comes.
  bool TrackEstimate(const Eigen::Ref<const Eigen::VectorXd>& theta, bool measured_noise_free = false);
  // Back to no estimate (y stands in for w, ε and v), as after construction.
  void ClearEstimate() {
    known_ = measured_w_ = fixed_ = false;
    tracked_ = 0;
  }
  // The output the estimator regresses on Next()'s z: y, or for RPEM while tracking ỹ = y + θ'(ψ − φ).
  double LinearisedOutput(double y) const;
  void PushOutput(double y);
  double PushCheckedOutput(double y, double y_hat, double scale, bool flagged, bool judged = true);
  void EndCleaningWarmUp() { arx_.EndCleaningWarmUp(); }
  // The A part's regressor holds a cleaned output (models/arx.h ArxRegressor::HoldsCleaned).
  bool HoldsCleaned() const { return arx_.HoldsCleaned(); }

  const PolynomialStructure& structure() const { return structure_; }
  Recursion recursion() const { return recursion_; }
  const OutputCleaner& cleaner() const { return arx_.cleaner(); }
  long projections() const { return projections_; }  // estimates refused by TrackEstimate

 private:
  void Store(double y);       // after the ARX part has stored y: the residual, noise and noise-free output
  void BoxJenkinsGradient();  // pre_ and psi_ for the current φ (RPEM, Box–Jenkins)
  // For each entry i in [begin, end): pre[i] = in[i] − Σ_{k<ng} g[k]·(the filter's value of entry i, k + 1
  // samples back), then (psi non-null) psi[i] = pre[i] + Σ_{k<nh} h[k]·(the same, k + 1 back). The taps
  // accumulate in registers, in the order k = 0, 1, …, two entries at a time. (No output aliases the history
  // or the other output: __restrict spares the compiler's run-time overlap tests.)
  void FilterRange(const double* g, int ng, const double* h, int nh, int begin, int end, const double* in,
                   double* __restrict pre, double* __restrict psi) const;
  // history[0 … n) ← [value, history[0 … n − 1)].
  static void Shift(double* history, int n, double value);

  PolynomialStructure structure_;
  ArxRegressor arx_;
  Eigen::VectorXd theta_;
  // φ(t): the ARX part from arx_; the C, D and F parts ε(t−1−k), −v(t−1−k), −w(t−1−k) are kept here
  // from sample to sample (Store shifts them), also before t0.
  Eigen::VectorXd phi_;
  Eigen::VectorXd work_;  // the stability test's buffer
  Recursion recursion_;
  Eigen::VectorXd psi_;  // ψ(t) (RPEM)
  // The filter's past: column newest_ + k holds ψ(t−1−k) for ARMAX and OE, p(t−1−k) for Box–Jenkins
  // (BoxJenkinsGradient), k < taps_ = nc (ARMAX), nf (OE) or max(nc + nf, nd) (Box–Jenkins). Each value is
  // stored twice (Store), in columns r and r + taps_, so that the taps' columns never wrap around.
  Eigen::MatrixXd history_;
  int taps_ = 0;
  Eigen::Index newest_ = 0;
  Eigen::VectorXd pre_, cf_;  // Box–Jenkins: p(t); C(q)F(q)'s coefficients
  bool box_jenkins_ = false;  // RPEM with F and C or D
  bool gradient_ = false;     // z = ψ(t) for the current sample
  bool known_ = false;        // an estimate has been given
  bool measured_w_ = false;   // w = y (TrackEstimate's measured_noise_free)
  bool fixed_ = false;        // SetEstimate's θ holds
  bool formed_ = false;       // φ(t) was formed for the current sample
  long samples_ = 0;
  long projections_ = 0;
  long tracked_ = 0;  // TrackEstimate calls since ClearEstimate
};

}  // namespace ident::models
