#include "studies/mems/mems_study.h"

#include <array>
#include <cmath>
#include <memory>
#include <random>

#include <fmt/format.h>
#include <Eigen/Cholesky>

#include "common/error.h"
#include "ident/observers/covariance_bound.h"
#include "ident/observers/grid_observer.h"
#include "ident/observers/grid_refinement.h"
#include "ident/observers/kalman_filter.h"
#include "ident/observers/lc_gaussian_filter.h"
#include "ident/observers/truncated_gaussian_filter.h"
#include "models/measurement.h"
#include "models/state_space.h"
#include "studies/mems/crossing_reading.h"
#include "studies/mems/excursion_reading.h"
#include "studies/mems/jackknife.h"
#include "studies/mems/window_ep_filter.h"

namespace ident {

std::string MemsStudyOptions::Validate() const {
  if (!(h > 0 && h < 1)) return fmt::format("h = {}; need 0 < h < 1", h);
  if (!(noise_intensity > 0)) return fmt::format("noise_intensity = {}; need > 0", noise_intensity);
  if (!(threshold > 0)) return fmt::format("threshold = {}; need > 0", threshold);
  if (!(t_target >= 10 * h)) return fmt::format("t_target = {}; need >= 10 h = {}", t_target, 10 * h);
  if (steps < 100 || steps > 1'000'000) return fmt::format("steps = {}; need 100..1000000", steps);
  if (burn_in < 0 || burn_in > steps - 10)  // at least one step per block of the calibration's jackknife
    return fmt::format("burn_in = {}; need 0 <= burn_in <= steps - 10", burn_in);
  if (grid_points < 16 || grid_points > 1024) return fmt::format("grid_points = {}; need 16..1024", grid_points);
  if (!(grid_tolerance >= 0 && grid_tolerance < 1))
    return fmt::format("grid_tolerance = {}; need 0 <= grid_tolerance < 1", grid_tolerance);
  if (ep_window < 1 || ep_window > 4096) return fmt::format("ep_window = {}; need 1..4096", ep_window);
  if (!(sigma_m2 >= 0)) return fmt::format("sigma_m2 = {}; need >= 0", sigma_m2);
  // At least one expected event in the scored part of the run (its mean spacing is t_target).
  const double scored_time = (steps - burn_in) * h;
  if (!(scored_time >= t_target))
    return fmt::format(
        "(steps - burn_in)·h = {:.3g} simulated seconds after the burn-in is shorter than t_target = "
        "{}, the mean time between events; need at least one expected event",
        scored_time, t_target);
  return "";
}

const MemsObserverResult& MemsStudyResult::Get(const std::string& name) const {
  for (const auto& o : observers)
    if (o.name == name) return o;
  IDENT_REQUIRE(false, "no observer named '{}' in the MEMS study", name);
  return observers.front();  // unreachable
}

double TunedSigmaO(double p11_stat, double noise_intensity) {
  IDENT_REQUIRE(p11_stat > 0 && noise_intensity > 0, "need p11_stat > 0 and noise intensity > 0");
  return std::cbrt(0.5) * std::pow(p11_stat, 2.0 / 3.0) * std::pow(noise_intensity, -1.0 / 6.0);  // [1, sec. V-B]
}

namespace {

// Sums of squared error and predicted variance after burn-in, also per contiguous block of the run for the
// calibration's jackknife standard error (studies/mems/jackknife.h). Blocks of whole stretches of the run keep the
// strong serial correlation of the errors (an error persists until the next event) inside a block.
struct Accumulator {
  static constexpr int kBlocks = 10;
  explicit Accumulator(int statistics_steps) : steps(statistics_steps) {}
  int steps;  // steps after burn-in
  double se = 0, var = 0;
  int n = 0;
  std::array<double, kBlocks> block_se{}, block_var{};
  void Add(double err, double predicted_var) {
    const int b = static_cast<int>(static_cast<long>(n) * kBlocks / steps);
    se += err * err;
    var += predicted_var;
    block_se[b] += err * err;
    block_var[b] += predicted_var;
    ++n;
  }
  MemsObserverResult Result(const std::string& name) const {
    return {name, std::sqrt(se / n), (var / n) / (se / n), JackknifeRatioStandardError(block_var, block_se)};
  }
};

}  // namespace

MemsStudyResult RunMemsStudy(const MemsStudyOptions& o) {
  const std::string problem = o.Validate();
  IDENT_REQUIRE(problem.empty(), "MEMS study: {}", problem);
  const auto model = models::MemsAccelerometerDynamics(o.h, o.noise_intensity);
  const Eigen::Vector2d c(1.0, 0.0);
  auto sensor = std::make_shared<models::ThresholdSensor>(c, o.threshold);
  const double v_ref = 2 * o.threshold / o.t_target;
  const double tau = o.t_target / 8;
  MemsStudyResult result;
  result.sigma_m2 = o.sigma_m2 > 0 ? o.sigma_m2 : (2 * o.h * v_ref) * (2 * o.h * v_ref) / 3;
  result.sigma_o = TunedSigmaO(1 / std::sqrt(3.0), o.noise_intensity);
  const double sigma_o13 = TunedSigmaO(1.0 / 3.0, o.noise_intensity);
  const double r_zero = result.sigma_o * result.sigma_o / o.h;  // measurement variance σ_o² h⁻¹
  const double r_zero13 = sigma_o13 * sigma_o13 / o.h;

  const Eigen::Vector2d m0(0.0, v_ref);
  Eigen::Matrix2d P0;
  P0 << 0.3, 0, 0, 1.0;
  // The grid observer runs after the simulation on the recorded inputs and readings (the control law does not
  // use it), at a refined size when grid_tolerance > 0 (ident/observers/grid_refinement.h).
  std::vector<Eigen::VectorXd> grid_u;
  std::vector<double> grid_y, truth_v, truth_x1;
  grid_u.reserve(o.steps);
  grid_y.reserve(o.steps);
  truth_v.reserve(o.steps);
  KalmanFilter tuned(m0, P0), tuned13(m0, P0);
  LcGaussianFilter plain(m0, P0), event(m0, P0), event_trunc(m0, P0), event_capped(m0, P0), wedge(m0, P0),
      excursion_filter(m0, P0), silent_filter(m0, P0);
  ExcursionReading excursion(*sensor, 2), silent_excursion(*sensor, 2);
  CovarianceBoundTracker bound(P0);
  WindowEpOptions wopt;
  wopt.window = o.ep_window;
  WindowEpFilter window_filter(*sensor, m0, P0, wopt);
  TruncatedGaussianFilter truncated_filter(*sensor, m0, P0);

  std::mt19937_64 rng(o.seed);
  std::normal_distribution<double> normal;
  const Eigen::Matrix2d L = Eigen::LLT<Eigen::Matrix2d>(Eigen::Matrix2d(model.process_noise)).matrixL();
  Eigen::Vector2d x(0.0, v_ref), w;
  Eigen::VectorXd u = Eigen::VectorXd::Zero(1);
  double y_prev = 0, direction = 1;
  const int statistics_steps = o.steps - o.burn_in;
  Accumulator acc_grid(statistics_steps), acc_tuned(statistics_steps), acc_tuned13(statistics_steps),
      acc_plain(statistics_steps), acc_event(statistics_steps), acc_trunc(statistics_steps),
      acc_capped(statistics_steps), acc_wedge(statistics_steps), acc_bound(statistics_steps),
      acc_excursion(statistics_steps), acc_silent(statistics_steps), acc_window(statistics_steps),
      acc_truncated(statistics_steps);
  Eigen::VectorXd wedge_mean_before(2);
  Eigen::MatrixXd wedge_cov_before(2, 2);
  Eigen::VectorXd excursion_mean_before(2);
  Eigen::MatrixXd excursion_cov_before(2, 2);
  Eigen::VectorXd silent_mean_before(2);
  Eigen::MatrixXd silent_cov_before(2, 2);
  int events_counted = 0;

  // Gaussian reading of x1 at `value` with variance r, as tilted moments (exact for a Gaussian).
  const models::GaussianMeasurement unit_reading(c, 1.0);
  auto gaussian_reading = [&](LcGaussianFilter& f, double value, double r) {
    const double s2 = f.covariance()(0, 0);
    const double m = f.mean()(0);
    const double g = s2 / (s2 + r);
    f.ApplyTilt(c, {0.0, m + g * (value - m), s2 * r / (s2 + r), true});
  };
  // First sample past a threshold at ±T (side = ±1; inward = −1 when leaving the outer region):
  // x1 = side (T + inward·h|v|/2), variance h²(v² + P22)/12.
  auto first_passage = [&](LcGaussianFilter& f, double side, double outward) {
    const double v = f.mean()(1);
    gaussian_reading(f, side * (o.threshold + outward * o.h * std::abs(v) / 2),
                     o.h * o.h * (v * v + f.covariance()(1, 1)) / 12 + 1e-12);
  };

  // Exact interval reading with its information capped at the σ_o rate h/σ_o² (p11 = 1/3): the tilted
  // moments (μ_t, v_t) of N(c'm, σ²) on the reading's interval equal a Gaussian reading z with variance
  // r = v_t σ²/(σ² − v_t), z = c'm + (μ_t − c'm)(σ² + r)/σ²; the reading is applied with
  // max(r, σ_o²/h) at z. Far from the thresholds r → ∞ (no pull toward 0); near them at most the
  // stationary information rate of [1, sec. V-B], so dependent repeated readings cannot collapse P.
  auto capped_reading = [&](LcGaussianFilter& f, double y) {
    const double s2 = f.covariance()(0, 0), m = f.mean()(0);
    const auto t = sensor->Tilt(y, m, s2);
    if (!t.ok || !(t.variance < s2)) return;
    const double r = t.variance * s2 / (s2 - t.variance);
    const double z = m + (t.mean - m) * (s2 + r) / s2;
    gaussian_reading(f, z, std::max(r, r_zero13));
  };

  for (int k = 0; k < o.steps; ++k) {
    // Truth, reading.
    for (int i = 0; i < 2; ++i) w(i) = normal(rng);
    x = model.A * x + model.B * u + L * w;
    const double y = sensor->Measure(x);
    const bool crossing = y != 0 && y_prev == 0;  // an event: 0 → ±1
    const bool leaving = y == 0 && y_prev != 0;   // back inside: ±1 → 0
    if (crossing) {
      direction = -y;
      if (k >= o.burn_in) ++events_counted;
    }
    // Observers: time update with u(k−1), then the reading y(k).
    grid_u.push_back(u);
    grid_y.push_back(y);
    truth_v.push_back(x(1));
    for (KalmanFilter* kf : {&tuned, &tuned13}) {
      kf->Predict(model, u);
      const double rz = kf == &tuned ? r_zero : r_zero13;
      if (crossing)
        kf->Correct(c, result.sigma_m2, y * o.threshold);
      else if (leaving)
        kf->Correct(c, result.sigma_m2, y_prev * o.threshold);
      else
        kf->Correct(c, rz, y * o.threshold);  // y = 0: x1 = 0; outside: x1 = ±T, both σ_o² h⁻¹
    }
    plain.Predict(model, u);
    plain.Correct(*sensor, y);
    event.Predict(model, u);
    event_trunc.Predict(model, u);
    event_capped.Predict(model, u);
    wedge_mean_before = wedge.mean();
    wedge_cov_before = wedge.covariance();
    wedge.Predict(model, u);
    excursion_mean_before = excursion_filter.mean();
    excursion_cov_before = excursion_filter.covariance();
    excursion_filter.Predict(model, u);
    // lc_excursion: the open excursion (entry wedge, repeated ±1, exit wedge) as one reading of the stacked
    // states (fixed-lag EP, studies/mems/excursion_reading.h); repeated y = 0 as in lc_wedge.
    bool excursion_done = false;
    if (crossing || leaving || excursion.active()) {
      excursion_done =
          excursion.Step(excursion_filter, excursion_mean_before, excursion_cov_before, model, u, y_prev, y).updated();
      if (excursion_done && !excursion.last_converged()) ++result.excursion_unconverged;
      if (!excursion_done && (crossing || leaving)) {
        ++result.excursion_fallbacks;
        if (!CorrectReadingChange(excursion_filter, excursion_mean_before, excursion_cov_before, model, *sensor, y_prev,
                                  y)
                 .updated()) {
          first_passage(excursion_filter, crossing ? y : y_prev, crossing ? 1.0 : -1.0);
        }
        excursion_done = true;
      }
    }
    if (!excursion_done) gaussian_reading(excursion_filter, y * o.threshold, r_zero13);
    // lc_excursion_silent (diagnostic): the same, but a repeated y = 0 is no reading at all (prediction only).
    silent_mean_before = silent_filter.mean();
    silent_cov_before = silent_filter.covariance();
    silent_filter.Predict(model, u);
    if (crossing || leaving || silent_excursion.active()) {
      if (!silent_excursion.Step(silent_filter, silent_mean_before, silent_cov_before, model, u, y_prev, y).updated() &&
          (crossing || leaving)) {
        CorrectReadingChange(silent_filter, silent_mean_before, silent_cov_before, model, *sensor, y_prev, y);
      }
    }
    if (crossing || leaving) {
      const double side = crossing ? y : y_prev, outward = crossing ? 1.0 : -1.0;
      first_passage(event, side, outward);
      first_passage(event_trunc, side, outward);
      first_passage(event_capped, side, outward);
      // The exact wedge of (x1(k−1), x1(k)); the first-passage reading only if the wedge has no mass.
      if (!CorrectReadingChange(wedge, wedge_mean_before, wedge_cov_before, model, *sensor, y_prev, y).updated()) {
        ++result.wedge_fallbacks;
        first_passage(wedge, side, outward);
      }
    } else {
      gaussian_reading(event, y * o.threshold, r_zero13);  // y = 0: x1 = 0; outside: x1 = ±T
      gaussian_reading(wedge, y * o.threshold, r_zero13);
      event_trunc.Correct(*sensor, y);
      capped_reading(event_capped, y);
    }
    // lc_window: every reading of the last W steps as an exact site, banded sliding-window EP.
    window_filter.Step(model, u, y);
    if (!window_filter.last_converged()) ++result.window_unconverged;
    // lc_truncated: assumed-density filter in the family of Gaussians restricted to the current reading's
    // interval (every reading exact, the hard edge kept in the family; ident/observers/truncated_gaussian_filter.h).
    truncated_filter.Step(model, u, y);
    bound.Predict(model);
    if (crossing) bound.UpdateStrength(c, 1.0 / result.sigma_m2);  // modified event measurement
    // Control law (causal in u and y): push back while outside, else track ∓v_ref with the tuned
    // Kalman filter's velocity estimate.
    u(0) = y != 0 ? -y * 2 * v_ref / tau : -(tuned.mean()(1) - direction * v_ref) / tau;
    y_prev = y;

    if (k >= o.burn_in) {
      acc_tuned.Add(tuned.mean()(1) - x(1), tuned.covariance()(1, 1));
      acc_tuned13.Add(tuned13.mean()(1) - x(1), tuned13.covariance()(1, 1));
      acc_plain.Add(plain.mean()(1) - x(1), plain.covariance()(1, 1));
      acc_event.Add(event.mean()(1) - x(1), event.covariance()(1, 1));
      acc_trunc.Add(event_trunc.mean()(1) - x(1), event_trunc.covariance()(1, 1));
      acc_capped.Add(event_capped.mean()(1) - x(1), event_capped.covariance()(1, 1));
      acc_wedge.Add(wedge.mean()(1) - x(1), wedge.covariance()(1, 1));
      acc_excursion.Add(excursion_filter.mean()(1) - x(1), excursion_filter.covariance()(1, 1));
      acc_silent.Add(silent_filter.mean()(1) - x(1), silent_filter.covariance()(1, 1));
      acc_window.Add(window_filter.mean()(1) - x(1), window_filter.covariance()(1, 1));
      acc_truncated.Add(truncated_filter.mean()(1) - x(1), truncated_filter.covariance()(1, 1));
      acc_bound.Add(0.0, bound.covariance()(1, 1));
    }
    if (o.record_trace) {
      auto& t = result.trace;
      t.t.push_back((k + 1) * o.h);
      t.x1.push_back(x(0));
      t.y.push_back(y);
      t.var_tuned_kalman.push_back(tuned.covariance()(1, 1));
      t.var_lc_gaussian.push_back(truncated_filter.covariance()(1, 1));
      t.var_bound.push_back(bound.covariance()(1, 1));
    }
  }
  auto run_grid = [&](int points) { return RunGridObserver(model, *sensor, m0, P0, grid_u, grid_y, {points, points}); };
  GridTrace grid;
  if (o.grid_tolerance > 0) {
    GridRefinementOptions ropt;
    ropt.points = o.grid_points;
    ropt.max_points = std::max(1024, FinerGridPoints(o.grid_points));
    ropt.tolerance = o.grid_tolerance;
    ropt.first_step = o.burn_in;
    GridRefinementResult refined = RefineGrid(run_grid, ropt);
    result.grid_points = refined.points;
    result.grid_coarse_points = refined.coarse_points;
    result.grid_difference = refined.difference;
    result.grid_converged = refined.converged;
    grid = std::move(refined.trace);
  } else {
    result.grid_points = o.grid_points;
    grid = run_grid(o.grid_points);
  }
  double grid_var_sum = 0;
  for (int k = 0; k < o.steps; ++k) {
    if (k >= o.burn_in) {
      acc_grid.Add(grid.mean[k](1) - truth_v[k], grid.variance[k](1));
      grid_var_sum += grid.variance[k](1);
    }
    if (o.record_trace) {
      result.trace.var_grid.push_back(grid.variance[k](1));
      const double e = grid.mean[k](1) - truth_v[k];
      result.trace.err2_grid.push_back(e * e);
    }
  }
  result.grid_mean_variance = grid_var_sum / (o.steps - o.burn_in);
  result.events = events_counted;
  result.t_mean =
      events_counted > 0 ? (o.steps - o.burn_in) * o.h / events_counted : std::numeric_limits<double>::infinity();
  result.observers.push_back(acc_grid.Result("grid"));
  result.observers.push_back(acc_tuned.Result("tuned_kalman"));
  result.observers.push_back(acc_tuned13.Result("tuned_kalman_13"));
  result.observers.push_back(acc_plain.Result("lc_plain"));
  result.observers.push_back(acc_event.Result("lc_event"));
  result.observers.push_back(acc_trunc.Result("lc_event_trunc"));
  result.observers.push_back(acc_capped.Result("lc_event_capped"));
  result.observers.push_back(acc_wedge.Result("lc_wedge"));
  result.observers.push_back(acc_excursion.Result("lc_excursion"));
  result.observers.push_back(acc_silent.Result("lc_excursion_silent"));
  result.observers.push_back(acc_window.Result("lc_window"));
  result.observers.push_back(acc_truncated.Result("lc_truncated"));
  result.window_failures = window_filter.failures();
  result.truncated_failures = truncated_filter.failures();
  result.truncated_projection_failures = truncated_filter.projection_failures();
  MemsObserverResult b{"bound", std::sqrt(acc_bound.var / acc_bound.n),
                       (acc_bound.var / acc_bound.n) / (acc_grid.se / acc_grid.n), 0.0};
  result.observers.push_back(b);
  // A run without an event, or with a figure that is not finite, has nothing to report.
  IDENT_REQUIRE(events_counted > 0,
                "MEMS study at t_target = {}: no event in the {:.3g} simulated seconds after the burn-in; raise the "
                "number of steps",
                o.t_target, (o.steps - o.burn_in) * o.h);
  for (const MemsObserverResult& r : result.observers)
    IDENT_REQUIRE(std::isfinite(r.rms) && std::isfinite(r.calibration),
                  "MEMS study at t_target = {}: observer '{}' has RMS {} and calibration {}, not finite numbers "
                  "(h = {} too small for double precision?)",
                  o.t_target, r.name, r.rms, r.calibration, o.h);
  return result;
}

}  // namespace ident
