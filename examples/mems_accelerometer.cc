// MEMS accelerometer with a threshold sensor (Henningsson & Åström 2006, sec. V).
//
// Problem: a test mass moves in one dimension under white-noise acceleration (intensity σ² = 1); the
// sensor only reports sign(x1) when |x1| ≥ 1. A control law bounces the mass between the thresholds so
// that events happen every t_target time units. Which observer estimates the velocity best?
// Model: models::MemsAccelerometerDynamics(h = 0.01, σ² = 1), models::ThresholdSensor(c = e1, T = 1).
// Output: for each rate, the RMS velocity error of the grid Bayesian observer, the paper's tuned Kalman
// filter, the log-concave Gaussian filter (lc_excursion: each excursion past a threshold one reading of
// the stacked states, fixed-lag EP) and the approximate covariance
// bound, with calibration (predicted variance / mean squared error). Look at how the errors grow with
// t_mean (the bound ~ σ² t/3 + 2σ_M²/t²) and how close the cheap filters stay to the grid observer.
// Usage: mems_accelerometer [steps] [grid_points]     (defaults 2000, 48: a quick run)
#include <cstdlib>
#include <iostream>

#include <fmt/format.h>

#include "studies/mems/mems_study.h"

int main(int argc, char** argv) {
  const int steps = argc > 1 ? std::atoi(argv[1]) : 2000;
  const int points = argc > 2 ? std::atoi(argv[2]) : 48;
  std::cout << fmt::format("{:>7} {:>6} {:>16} {:>16} {:>16} {:>16}\n", "t_mean", "events", "grid", "tuned_kalman",
                           "lc_gaussian", "bound");
  unsigned seed = 1;
  for (double t : {0.3, 0.5, 1.0, 1.5, 2.0, 3.0}) {
    ident::MemsStudyOptions o;
    o.t_target = t;
    o.steps = steps;
    o.burn_in = steps / 10;
    o.grid_points = points;
    o.seed = seed++;
    const auto r = ident::RunMemsStudy(o);
    std::cout << fmt::format("{:7.3f} {:6d}", r.t_mean, r.events);
    for (const char* name : {"grid", "tuned_kalman", "lc_excursion", "bound"})
      std::cout << fmt::format(" {:8.4f} ({:4.2f})", r.Get(name).rms, r.Get(name).calibration);
    std::cout << "\n";
  }
  return 0;
}
