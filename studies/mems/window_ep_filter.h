// Sliding-window expectation propagation (EP) for a 2-state model read by a threshold sensor: every
// reading of the last W steps is an exact log-concave site of the state chain, refined jointly by a
// banded (Kalman-smoother) EP; sites leaving the window are frozen into the filtering prior.
//
// Why: the plain assumed-density filter projects 1{|x1(k)| < T} onto a Gaussian at every step and then
// truncates that projection again at k + 1, although x1(k+1) < T is largely implied by x1(k) < T and the
// dynamics (strongly dependent readings counted as if independent: the collapse of lc_plain,
// docs/explanation/observers.md). Keeping the recent readings as factors of the stacked states and refitting each
// against a cavity that already contains the others' information (EP, Minka 2001) removes the
// re-truncation between readings inside the window; the paper's stationary σ_o reading is not used.
//
// Model. Augmented state z(j) = (x(j), s(j−1)), s(j) = c'x(j) (the lagged position makes a change of
// reading a site of one z): z(j) = F z(j−1) + b_j + w_j, F = [A 0; c' 0], b_j = [B u(j−1); 0],
// w_j ~ N(0, Q), Q = [P_N 0; 0 0]. Exact posterior over the window j = 1..L:
//   p(z(0..L) | y) ∝ N(z(0); base) Π_j N(z(j); F z(j−1) + b_j, Q) Π_j t_j(z(j))
// with t_j the reading of step j as an indicator (log-concave, [1, sec. IV]):
//   repeated reading y(j) = y(j−1):  1{s(j) ∈ R(y(j))}, R(0) = (−T, T), R(±1) = ±[T, ∞)
//   change y(j−1) ≠ y(j):            the wedge of (s(j−1), s(j)) of studies/mems/crossing_reading.h, which
//                                    takes over the reading of step j−1 (its 1-D site is removed, so
//                                    every reading is counted once); after a change at j−1 the wedge's
//                                    reading of s(j−1) is already in site j−1 and site j is 1-D (so is
//                                    it for W = 1). Steps are appended, then the oldest frozen.
// base = the filtering distribution of z(0) with all older sites frozen. EP keeps a Gaussian site
// g_j(z) = exp(−½ z'H'λ_jHz + η_j'Hz) per reading (H selects s(j) or (s(j−1), s(j))); the refit of site
// j is the exact moment match of t_j × cavity_j, cavity_j = α⁻_j · β_j, where α⁻_j (moment form,
// forward message of sites < j) and β_j (information form, backward message of sites > j) are the
// Kalman filter / backward information filter of the chain with the other sites as pseudo-readings:
//   α⁻_j = N(F m_{j−1} + b_j, F P_{j−1} F' + Q);  α_j = α⁻_j · g_j:  P ← (I + P Λ)⁻¹ P,
//          m ← m + P (η_z − Λ m), Λ = H'λH, η_z = H'η
//   β_{j−1}: Ω' = Ω_j + Λ_j, ω' = ω_j + η_z,j, S = (I + Ω'Q)⁻¹ Ω', σ = (I + Ω'Q)⁻¹ ω',
//          Ω_{j−1} = F'SF, ω_{j−1} = F'(σ − S b_j)
//   cavity: P_c = (I + P⁻Ω)⁻¹ P⁻, m_c = m⁻ + P_c (ω − Ω m⁻)
//   new site: λ = V_t⁻¹ − V_c⁻¹ (≥ 0: a log-concave factor shrinks the cavity, Brascamp–Lieb [1, Thm 2];
//          round-off clipped), η = V_t⁻¹ μ_t − V_c⁻¹ μ_c, (μ_t, V_t) the exact moments of the cavity's
//          projection truncated to the site's region (1-D truncated normal or Tallis' quadrant moments).
// One sweep = a backward pass (refit j = L … 1 with fresh β_j and the stored α⁻_j, so each refit is a
// sequential EP step of the current approximation, Heskes & Zoeter 2002) and a forward pass of the
// messages α (no refits: the fixed point is the same, at half the tilted-moment evaluations), starting at
// the oldest site the backward pass changed (α_j depends on sites ≤ j only); O(L) per sweep with 3 × 3
// blocks, 2 × 2 where the structure allows it: F's third column is zero, so β_j never involves s(j−1) and
// a 1-D site's cavity, the backward message through it and the time update need only the x block. The new
// site is first fitted alone (β = 0). Sweeps stop when no
// site's tilted moments move by more than `tolerance` (relative to their sd / variance); a site whose cavity
// moved less than that since its last refit keeps its value (no erfc / Owen's T). A 1-D site whose
// cavity has its bounds more than 8.5 sd away is the identity to double precision (mass outside < 1e-17)
// and is set to zero without evaluating erfc. With W = 1 the filter is the plain assumed-density filter
// (lc_plain: exact interval moments at every step; a wedge needs the previous reading inside the window);
// W → ∞ is EP smoothing of all readings. W is an approximation parameter (like the grid's
// points), chosen by convergence of the results in W, not fitted.
//
// Example:
//   ident::WindowEpFilter f(sensor, m0, P0, {.window = 32});
//   for (...) { f.Step(model, u, y); use(f.mean(), f.covariance()); }   // u = u(k−1), y = y(k)
//
// Storage is allocated at construction; Step allocates nothing. Only 2-state models and a threshold
// sensor (the MEMS case of [1, sec. V]).
//
// [1] T. Henningsson, K. J. Åström, "Log-concave Observers", MTNS 2006.
// [2] T. P. Minka, "Expectation propagation for approximate Bayesian inference", UAI 2001.
// [3] T. Heskes, O. Zoeter, "Expectation propagation for approximate inference in dynamic Bayesian
//     networks", UAI 2002.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "common/step_report.h"
#include "models/measurement.h"
#include "models/state_space.h"

namespace ident {

struct WindowEpOptions {
  int window = 16;          // readings refined jointly (W ≥ 1); older sites are frozen
  int max_sweeps = 20;      // EP sweeps per step
  double tolerance = 1e-6;  // convergence of the sites' tilted moments (relative to their sd / variance);
                            // a site whose cavity moved less than this is not refitted
};

class WindowEpFilter {
 public:
  using Vec3 = Eigen::Vector3d;
  using Mat3 = Eigen::Matrix3d;

  // Throws InvalidArgument for a sensor that is not on 2 states, a prior that is not finite / symmetric
  // positive semidefinite, window < 1, max_sweeps < 1 or tolerance ≤ 0.
  WindowEpFilter(const models::ThresholdSensor& sensor, const Eigen::Vector2d& mean, const Eigen::Matrix2d& covariance,
                 WindowEpOptions options = {});

  // One step: time update with u = u(k−1), then the reading y = y(k) ∈ {−1, 0, 1}. kRejectedInvalid (state
  // unchanged) for a model that is not 2-state, u of the wrong size or not finite, or an invalid reading.
  // A site with no mass under its cavity (the reading impossible under the approximation) keeps its
  // previous value (zero if new) and is counted in failures(); the step is still kUpdated.
  StepReport Step(const models::LinearStateSpace& model, const Eigen::Ref<const Eigen::VectorXd>& u, double y);

  Eigen::Vector2d mean() const;        // filtering mean of x(k)
  Eigen::Matrix2d covariance() const;  // filtering covariance of x(k)
  // EP's smoothed marginal of x(k − lag), lag = 0 … length() − 1 (lag 0 = mean()/covariance()).
  void SmoothedMarginal(int lag, Eigen::Vector2d& mean, Eigen::Matrix2d& covariance) const;

  int length() const { return count_; }  // readings in the window
  int last_sweeps() const { return last_sweeps_; }
  bool last_converged() const { return last_converged_; }
  long failures() const { return failures_; }  // site refits with no mass
  long refits() const { return refits_; }      // tilted-moment evaluations so far (cost diagnostic)

 private:
  struct Slot {
    Mat3 F, Q;
    Vec3 b;
    int dim = 0;  // 0: no site, 1: s(j) ∈ [lo, hi], 2: quadrant of (s(j−1), s(j))
    double lo = 0, hi = 0;
    Eigen::Vector2d bounds, sides;
    Eigen::Matrix2d lambda;  // site precision on (s) or (s(j−1), s(j))
    Eigen::Vector2d eta;
    Eigen::Vector2d last_mean;  // tilted moments of the last refit (NaN before the first)
    Eigen::Matrix2d last_cov;
    Eigen::Vector2d cav_mean;  // cavity (on the site's coordinates) of the last refit
    Eigen::Matrix2d cav_cov;
    Vec3 pred_m, filt_m, omega;  // α⁻_j, α_j (moment form), β_j (information form)
    Mat3 pred_P, filt_P, Omega;
  };
  Slot& At(int j) { return ring_[static_cast<size_t>((head_ + j) % capacity_)]; }
  const Slot& At(int j) const { return ring_[static_cast<size_t>((head_ + j) % capacity_)]; }
  // Refit slot's site against the cavity α⁻ · β; returns the largest relative move of the tilted moments
  // (0 for an unchanged site), or −1 if the region has no mass under the cavity (site kept).
  double Refit(Slot& s);
  void Forward(Slot& s, const Vec3& m_prev, const Mat3& P_prev);  // α⁻_j and α_j from α_{j−1}
  void Filtered(Slot& s);                                         // α_j from α⁻_j and the site
  void Backward(const Slot& s, Slot& prev);                       // β_{j−1} from β_j and site j

  Eigen::Vector3d h_;  // H row of s(j) in z: (c, 0)
  double threshold_ = 0;
  WindowEpOptions options_;
  std::vector<Slot> ring_;
  int capacity_ = 0, head_ = 0, count_ = 0;
  Vec3 base_m_;  // filtering distribution of z at the step before the window
  Mat3 base_P_;
  double y_prev_ = 0;
  bool have_prev_ = false;
  int last_sweeps_ = 0;
  bool last_converged_ = true;
  long failures_ = 0, refits_ = 0;
};

}  // namespace ident
