#include "ident/observers/grid_refinement.h"

#include <algorithm>
#include <cmath>

#include "common/error.h"
#include "ident/observers/grid_observer.h"

namespace ident {

GridTrace RunGridObserver(const models::LinearStateSpace& model, const models::MeasurementFunction& measurement,
                          const Eigen::VectorXd& m0, const Eigen::MatrixXd& P0, const std::vector<Eigen::VectorXd>& u,
                          const std::vector<double>& y, const std::vector<int>& points) {
  IDENT_REQUIRE(u.size() == y.size(), "RunGridObserver: {} inputs for {} readings", u.size(), y.size());
  GridObserverOptions options;
  options.points = points;
  GridObserver grid(m0, P0, options);
  GridTrace trace;
  trace.mean.reserve(y.size());
  trace.variance.reserve(y.size());
  for (size_t k = 0; k < y.size(); ++k) {
    if (!grid.Predict(model, u[k]).updated())
      ++trace.failed_steps;
    else if (!grid.Correct(measurement, y[k]).updated())
      ++trace.failed_steps;
    trace.mean.push_back(grid.mean());
    trace.variance.push_back(grid.covariance().diagonal());
  }
  return trace;
}

double GridTraceDifference(const GridTrace& a, const GridTrace& b, int first_step) {
  IDENT_REQUIRE(a.mean.size() == b.mean.size() && !a.mean.empty(), "grid traces of {} and {} steps", a.mean.size(),
                b.mean.size());
  const size_t first = std::min(static_cast<size_t>(std::max(first_step, 0)), a.mean.size() - 1);
  const Eigen::Index dim = a.mean.front().size();
  double worst = 0;
  for (Eigen::Index i = 0; i < dim; ++i) {
    double dv = 0, vb = 0, dm2 = 0;
    for (size_t k = first; k < a.mean.size(); ++k) {
      dv += std::abs(a.variance[k](i) - b.variance[k](i));
      vb += b.variance[k](i);
      dm2 += (a.mean[k](i) - b.mean[k](i)) * (a.mean[k](i) - b.mean[k](i));
    }
    worst = std::max({worst, dv / vb, std::sqrt(dm2 / vb)});
  }
  return std::isnan(worst) ? std::numeric_limits<double>::infinity() : worst;
}

int FinerGridPoints(int points) {
  const int finer = (3 * points + 1) / 2;
  return finer + (finer % 2);
}

GridRefinementResult RefineGrid(const std::function<GridTrace(int points)>& run, const GridRefinementOptions& o) {
  IDENT_REQUIRE(o.points >= 8, "grid refinement: points = {}; need >= 8", o.points);
  IDENT_REQUIRE(o.max_points >= FinerGridPoints(o.points),
                "grid refinement: max_points = {}; need >= {} (one refinement of points = {})", o.max_points,
                FinerGridPoints(o.points), o.points);
  IDENT_REQUIRE(o.tolerance > 0, "grid refinement: tolerance = {}; need > 0", o.tolerance);
  GridRefinementResult r;
  int coarse = o.points;
  GridTrace a = run(coarse);
  for (;;) {
    const int fine = FinerGridPoints(coarse);
    GridTrace b = run(fine);
    r.coarse_points = coarse;
    r.points = fine;
    r.difference = GridTraceDifference(a, b, o.first_step);
    r.converged = r.difference <= o.tolerance;
    if (r.converged || FinerGridPoints(fine) > o.max_points) {
      r.trace = std::move(b);
      return r;
    }
    coarse = fine;
    a = std::move(b);
  }
}

}  // namespace ident
