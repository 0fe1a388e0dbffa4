// Grid refinement check for the grid observer (grid_observer.h): run the same readings on an N^d grid
// and on a finer one (factor 1.5 per axis, rounded to even) and accept the finer run when their moments
// agree within a stated tolerance; otherwise the grid grows and the check repeats.
//
// Agreement, per state component i over the scored steps k (from first_step on):
//   variance  Σ_k |v_a,k − v_b,k| / Σ_k v_b,k              ≤ tolerance
//   mean      √(Σ_k (m_a,k − m_b,k)²) / √(Σ_k v_b,k)        ≤ tolerance   (in posterior standard deviations)
// with a the coarser and b the finer run. The discretisation error of the moments falls at least like Δ²
// (grid_observer.h), so the finer grid is within about tolerance/(1.5² − 1) ≈ 0.8·tolerance of the limit.
//
// Example:
//   auto run = [&](int points) { return RunGridObserver(model, sensor, m0, P0, u, y, {points, points}); };
//   GridRefinementResult r = RefineGrid(run, {.points = 64, .tolerance = 0.01});
//   r.points;   // the grid used, r.trace its moments; r.difference the agreement with r.coarse_points
#pragma once

#include <functional>
#include <memory>
#include <vector>

#include <Eigen/Core>

#include "models/measurement.h"
#include "models/state_space.h"

namespace ident {

// Per-step posterior mean and variances (diagonal of the covariance) of one run.
struct GridTrace {
  std::vector<Eigen::VectorXd> mean, variance;
  int failed_steps = 0;  // Predict or Correct not taken
};

// The grid observer (default options, `points` per axis) on the readings y(k) with inputs u(k − 1)
// (u[k] is applied before reading y[k]), from N(m0, P0).
GridTrace RunGridObserver(const models::LinearStateSpace& model, const models::MeasurementFunction& measurement,
                          const Eigen::VectorXd& m0, const Eigen::MatrixXd& P0, const std::vector<Eigen::VectorXd>& u,
                          const std::vector<double>& y, const std::vector<int>& points);

struct GridRefinementOptions {
  int points = 64;          // first (coarser) grid, points per axis; ≥ 8
  int max_points = 512;     // the finer grid never exceeds this
  double tolerance = 0.01;  // see the header comment; > 0
  int first_step = 0;       // steps before it are not compared (burn-in)
};

struct GridRefinementResult {
  int points = 0;          // the finer grid of the last comparison, whose moments are `trace`
  int coarse_points = 0;   // the coarser grid it was compared with
  double difference = 0;   // largest relative moment difference between them (header comment)
  bool converged = false;  // difference ≤ tolerance (false: max_points reached first)
  GridTrace trace;
};

// The relative moment difference of run a against run b (header comment).
double GridTraceDifference(const GridTrace& a, const GridTrace& b, int first_step);
// Runs run(points) on growing grids until two successive ones agree. Throws InvalidArgument on bad options.
GridRefinementResult RefineGrid(const std::function<GridTrace(int points)>& run, const GridRefinementOptions& options);
// The next grid size of the refinement: 1.5 · points rounded up to even.
int FinerGridPoints(int points);

}  // namespace ident
