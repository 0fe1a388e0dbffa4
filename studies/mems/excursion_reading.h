// A threshold sensor's excursion (the event 0 → ±1, the repeated ±1 readings, the return ±1 → 0) as one
// log-concave reading of the stacked states, for the log-concave Gaussian filter: a fixed-lag
// expectation-propagation (EP) smoother over s = (c'x(k_e − 1), c'x(k_e), …, c'x(k)), k_e the event step.
//
// Why: the exit wedge x1(k−1) ≥ T > x1(k) a few steps after the entry wedge x1(k_e−1) < T ≤ x1(k_e) is
// largely implied by the entry and the dynamics. A Gaussian filter that projects after the entry has lost
// the entry's hard edge and re-truncates its projection at the exit (the dependency that collapses the
// plain assumed-density filter, on a small scale; docs/explanation/observers.md). Here every reading since k_e − 1
// stays a factor of its own on the jointly Gaussian stacked prediction:
//   p(s, x(k) | readings) ∝ N((s, x(k)); μ0, Σ0) · 1{entry wedge}(s_{k_e−1}, s_{k_e})
//                            · Π_{k_e < j < k} 1{y s_j ≥ T} · 1{exit wedge}(s_{k−1}, s_k)
// — a Gaussian restricted to an intersection of half-spaces, so log-concave [1, sec. IV]; the filter's
// state is its marginal of x(k) (with x(k) | s Gaussian). The exact marginal needs a (k − k_e + 2)-variate
// orthant integral; EP [Minka 2001] approximates each factor t_i by a Gaussian site q_i and refits it
// against the exact moments of t_i times the cavity (posterior without q_i): 1-D truncated normal for a
// repeated reading, Tallis' bivariate moments (models/truncated_bivariate_normal.h) for a wedge. One pass
// in time order is the sequential (assumed-density) filter; EP revisits the earlier factors with the later
// ones' information in their cavity, so the entry factor is refitted once the exit is known. Each factor
// is log-concave, so each refit shrinks the cavity's covariance (Brascamp–Lieb, [1, Thm 2]): every site
// precision is ≥ 0 and every cavity a proper Gaussian. With a single factor (the step of the event) EP is
// exact and equals studies/mems/crossing_reading.h's wedge update.
//
// Joint update for a factor on coordinates A with target marginal N(μ_A', Σ_AA') (exact for a Gaussian
// joint, no inverse of the whole covariance): K = Σ_{·A} Σ_AA⁻¹, μ ← μ + K(μ_A' − μ_A),
// Σ ← Σ + K(Σ_AA' − Σ_AA)K'. Time update (factors depend on s only): μ_x ← Aμ_x + Bu,
// Σ_xx ← AΣ_xxA' + P_N, Σ_xs ← AΣ_xs, then s_k = c'x(k) is appended.
//
// Example (inside a filter loop; `f` an LcGaussianFilter, m_before/P_before its state before Predict):
//   ident::ExcursionReading ex(sensor, /*max_length=*/64);
//   f.Predict(model, u);
//   if (ex.active() || y != y_prev) ex.Step(f, m_before, P_before, model, u, y_prev, y);  // writes f's state
//   else f.ApplyTilt(...);                                                               // y = 0 repeated
//
// Cost per step inside an excursion of length L: sweeps × L factor refits, each O((L + n)²). The joint's
// storage for max_length readings is allocated at construction, but the time update allocates small
// temporaries: not for hard real time (unlike BasicLcGaussianFilter). Past max_length steps the excursion is closed
// (the state kept) and later readings of it are left to the caller (Step returns kRejectedInvalid).
//
// [1] T. Henningsson, K. J. Åström, "Log-concave Observers", MTNS 2006.
// [2] T. P. Minka, "Expectation propagation for approximate Bayesian inference", UAI 2001.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "common/step_report.h"
#include "ident/observers/lc_gaussian_filter.h"
#include "models/measurement.h"
#include "models/state_space.h"

namespace ident {

struct ExcursionOptions {
  int max_length = 64;       // stacked readings kept (an excursion longer than this is closed)
  int max_sweeps = 50;       // EP sweeps per step
  double tolerance = 1e-10;  // stop when no site mean/variance target moves by more than this (relative)
};

class ExcursionReading {
 public:
  // Throws InvalidArgument for max_length < 2, max_sweeps < 1 or tolerance ≤ 0.
  ExcursionReading(const models::ThresholdSensor& sensor, int num_states, ExcursionOptions options = {});

  // One step of the filter with the reading change y_prev → y (or a repeated ±1 inside an excursion).
  // `filter` has been predicted once with (model, u) from (mean_before, cov_before). Starts an excursion
  // at 0 → ±1, adds the repeated reading, closes it at ±1 → 0; writes the marginal of x(k) to the filter.
  // kRejectedInvalid (nothing done) for y == y_prev outside an excursion, readings not in {−1, 0, 1},
  // sizes that do not fit or an excursion past max_length; kNumericalFailure (excursion dropped, filter
  // untouched) if a factor has no mass to double precision.
  StepReport Step(LcGaussianFilter& filter, const Eigen::Ref<const Eigen::VectorXd>& mean_before,
                  const Eigen::Ref<const Eigen::MatrixXd>& cov_before, const models::LinearStateSpace& model,
                  const Eigen::Ref<const Eigen::VectorXd>& u, double y_prev, double y);

  bool active() const { return length_ > 0; }
  int length() const { return length_; }            // stacked readings s (0 when no excursion is open)
  int last_sweeps() const { return last_sweeps_; }  // EP sweeps of the last Step
  bool last_converged() const { return last_converged_; }
  // Posterior moments of the joint (x(k), s) after the last Step: first n entries x(k), then s.
  Eigen::VectorXd joint_mean() const { return mu_.head(n_ + length_); }
  Eigen::MatrixXd joint_covariance() const { return sigma_.topLeftCorner(n_ + length_, n_ + length_); }

 private:
  struct Factor {
    int first = 0;                  // index of its first s (0-based in s)
    int dim = 0;                    // 1 or 2 (2: s_first, s_first+1)
    Eigen::Vector2d bounds, sides;  // region {sides_i (s_i − bounds_i) > 0}
    Eigen::Matrix2d lambda;         // site precision (dim × dim block used)
    Eigen::Vector2d eta;            // site precision × mean
    Eigen::Vector2d last_mean;      // tilted moments of the last refit (convergence check)
    Eigen::Matrix2d last_cov;
    Eigen::Vector2d cavity_mean;  // cavity of the last refit: an unchanged cavity needs no refit
    Eigen::Matrix2d cavity_cov;
  };
  // Refit factor f (EP step); returns the largest relative change of its tilted moments, or −1 if the
  // factor has no mass.
  double Refit(Factor& f);
  // Remove factor f's site from the posterior (posterior ← cavity).
  void Remove(const Factor& f);
  // Update the joint so that its marginal on the factor's coordinates becomes N(mean, cov).
  void SetMarginal(const Factor& f, const Eigen::Vector2d& mean, const Eigen::Matrix2d& cov);
  void Cavity(const Factor& f, Eigen::Vector2d& mean, Eigen::Matrix2d& cov) const;
  void Propagate(const models::LinearStateSpace& model, const Eigen::Ref<const Eigen::VectorXd>& u);
  void AppendReadingCoordinate();
  StepReport Sweep(LcGaussianFilter& filter);

  Eigen::VectorXd c_;
  double threshold_ = 0;
  ExcursionOptions options_;
  int n_ = 0, length_ = 0, last_sweeps_ = 0;
  bool last_converged_ = false;
  double side_ = 0;  // +1 / −1: the threshold of the open excursion
  Eigen::VectorXd mu_, work_v_;
  Eigen::MatrixXd sigma_, gain_, work_m_;
  std::vector<Factor> factors_;
};

}  // namespace ident
