// The MEMS accelerometer study of Henningsson & Åström (2006, sec. V): one simulated run at a given
// event rate, observed by the grid Bayesian observer, the tuned Kalman filter of sec. V-B, variants of
// the log-concave Gaussian filter and the approximate covariance bound of sec. V-A.
//
//   Dynamics:  models::MemsAccelerometerDynamics(h, σ²), sensor y = sign(x1) if |x1| ≥ T (T = 1).
//   Control:   ping-pong between the thresholds. After an event of sign s the velocity reference is
//              −s·v_ref, v_ref = 2 T / t_target, and u = −(x̂2 − v_ref_signed)/τ, τ = t_target/8, with x̂2
//              from the tuned Kalman filter (a function of past u and y only, so every observer sees an
//              exogenous input). The measured mean time between events is reported.
//   Events:    a "crossing" is a step with y(k) ≠ 0 and y(k−1) = 0 (the first sample past a threshold).
//
// Observers (all on the same u, y):
//   grid            GridObserver, exact threshold sensor (the reference); with grid_tolerance > 0 at the size
//                   RefineGrid (ident/observers/grid_refinement.h) accepts, starting at grid_points
//   tuned_kalman    KalmanFilter, y = 0 as x1 = 0 with variance σ_o²/h, σ_o = 2^(−1/3) p11^(2/3) σ^(−1/3),
//                   p11 = 1/√3 as printed in the paper; crossings as x1 = y T with variance σ_M²
//   tuned_kalman_13 the same with p11 = 1/3 (the variance of the rectangular distribution on (−1, 1))
//   lc_plain        LcGaussianFilter, exact tilted moments every step (assumed-density filter; baseline)
//   lc_event        LcGaussianFilter with the first-passage event model: a crossing reading is the
//                   Gaussian x1 = y (T + h|x̂2|/2) with variance h²(x̂2² + P22)/12 (crossing time uniform
//                   in the step; likewise the first sample back inside, at y_prev (T − h|x̂2|/2)); every
//                   other reading (y = 0 inside, y = ±1 still outside) is the σ_o reading x1 = y T with
//                   variance σ_o²/h, p11 = 1/3: successive equal readings carry little new information
//                   [1, sec. V-B], and exact moments at each of them collapse the filter (lc_plain)
//   lc_event_trunc  first-passage event model, but exact interval moments for every other reading
//   lc_event_capped first-passage event model, exact interval readings with information capped at h/σ_o²
//   lc_wedge        every change of reading y(k−1) ≠ y(k) is the exact wedge of the
//                   lagged pair (x1(k−1), x1(k)), e.g. x1(k−1) < T ≤ x1(k) (studies/mems/crossing_reading.h: a
//                   log-concave reading of the augmented state, Tallis moments, exact update of x(k));
//                   every repeated reading is the σ_o reading of lc_event (p11 = 1/3)
//   lc_excursion    as lc_wedge, but an excursion past a threshold (entry wedge, repeated ±1 readings, exit
//                   wedge) is one log-concave reading of the stacked states x(k_e − 1 … k): fixed-lag
//                   expectation propagation with exact 1-D/2-D factor moments (studies/mems/excursion_reading.h)
//   lc_excursion_silent  diagnostic: lc_excursion with no reading at repeated y = 0 (prediction only
//                   between excursions), to see what the σ_o reading contributes
//   lc_window       every reading of the last W = ep_window steps an exact site of the state chain (repeated
//                   y = 0 as 1{|x1| < T}, repeated ±1 as half-lines, changes as the wedge of lc_wedge), refined
//                   jointly by banded sliding-window EP; older sites frozen (studies/mems/window_ep_filter.h).
//                   No σ_o.
//   lc_truncated    (the CLI's lc_gaussian) assumed-density filter in the family of Gaussians restricted to the
//                   current reading's interval: each step the exact moments of the pushed-forward restricted density on
//                   the rectangle R(y(k−1)) × R(y(k)), then the KL projection back onto the family
//                   (ident/observers/truncated_gaussian_filter.h). No σ_o, no window.
//   bound           CovarianceBoundTracker with the modified event measurement: crossing ∈ LC(Q_M),
//                   Q_M = diag(σ_M⁻², 0), y = 0 ∈ LC(0); rms = √(mean P̄22)
//
// For each: RMS velocity error over the steps after burn-in, and calibration = mean predicted
// velocity variance / mean squared velocity error (1 = calibrated, < 1 = overconfident), with the
// calibration's jackknife standard error over 10 contiguous blocks of the run: the ratio of two averages
// over a few events is noisy (the exact posterior's own calibration is 1 only in expectation).
#pragma once

#include <limits>
#include <string>
#include <vector>

namespace ident {

struct MemsStudyOptions {
  double h = 0.01;               // sampling period
  double noise_intensity = 1.0;  // σ²
  double threshold = 1.0;        // T
  double t_target = 1.0;         // control law's target time between events
  int steps = 10000;             // simulated steps
  int burn_in = 500;             // steps excluded from the statistics
  unsigned seed = 1;
  int grid_points = 128;      // per axis of the 2-D grid observer (the first grid when grid_tolerance > 0)
  double grid_tolerance = 0;  // > 0: refine the grid until its moments agree with a finer one to this
  double sigma_m2 = 0.0;      // σ_M² of the modified event measurement; 0 = (2 h v_ref)²/3
  bool record_trace = false;  // keep per-step variances (Fig. 8)
  int ep_window = 16;         // lc_window's EP window W (readings refined jointly)
  std::string Validate() const;
};

struct MemsObserverResult {
  std::string name;
  double rms = 0;             // RMS velocity error (bound: √ mean P̄22)
  double calibration = 0;     // mean predicted var(x2) / mean squared error (bound: mean P̄22 / grid MSE)
  double calibration_se = 0;  // its jackknife standard error over 10 contiguous blocks of the run (bound: 0)
};

struct MemsTrace {
  std::vector<double> t, x1, var_grid, var_tuned_kalman, var_lc_gaussian /* lc_truncated */, var_bound, err2_grid, y;
};

struct MemsStudyResult {
  double t_mean = 0;  // measured mean time between events
  int events = 0;
  std::vector<MemsObserverResult> observers;  // in the order listed in the header comment
  double sigma_o = 0;                         // σ_o used by tuned_kalman (p11 = 1/√3)
  double sigma_m2 = 0;
  int wedge_fallbacks = 0;        // changes of reading where lc_wedge's wedge had no mass (first-passage reading used)
  int excursion_fallbacks = 0;    // changes of reading lc_excursion left to lc_wedge's update (no mass / too long)
  int excursion_unconverged = 0;  // lc_excursion steps whose EP sweeps hit the limit
  long window_failures = 0;       // lc_window site refits with no mass under the cavity (site kept)
  int window_unconverged = 0;     // lc_window steps whose EP sweeps hit the limit
  long truncated_failures = 0;    // lc_truncated steps whose rectangle had no mass (fallback)
  long truncated_projection_failures = 0;  // lc_truncated projections without a parent (see its header)
  int grid_points = 0;                     // points per axis of the grid whose moments are reported
  int grid_coarse_points = 0;              // the coarser grid of the refinement check (0: no check)
  double grid_difference = std::numeric_limits<double>::quiet_NaN();  // their relative moment difference
  bool grid_converged = false;                                        // grid_difference ≤ grid_tolerance
  double grid_mean_variance = 0;  // mean predicted var(x2) of the grid after burn-in
  MemsTrace trace;
  const MemsObserverResult& Get(const std::string& name) const;
};

// Throws InvalidArgument naming the option if options are invalid.
MemsStudyResult RunMemsStudy(const MemsStudyOptions& options);

// σ_o = 2^(−1/3) p11^(2/3) σ^(−1/3)  [1, sec. V-B]; σ = √(noise intensity).
double TunedSigmaO(double p11_stat, double noise_intensity);

}  // namespace ident
