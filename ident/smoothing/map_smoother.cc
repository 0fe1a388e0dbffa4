#include "ident/smoothing/map_smoother.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "common/error.h"
#include "ident/smoothing/internal/interior_point.h"
#include "ident/smoothing/internal/map_smoother_fast_path.h"

namespace ident {

using models::Penalty;
using models::PlqForm;

const models::Penalty& MapSmootherProblem::ft(int t) const {
  if (process.size() == 1) return process[0];
  if (process.size() == 2) return t == 0 ? process[0] : process[1];
  return process[t];
}

const char* ToString(MapSmootherStatus status) {
  switch (status) {
    case MapSmootherStatus::kConverged:
      return "converged";
    case MapSmootherStatus::kMaxIterations:
      return "max_iterations";
    case MapSmootherStatus::kInfeasible:
      return "infeasible";
    case MapSmootherStatus::kNumericalFailure:
      return "numerical_failure";
    case MapSmootherStatus::kStalled:
      return "stalled";
  }
  return "?";
}

std::string MapSmootherOptions::Validate() const {
  if (max_iterations < 1) return fmt::format("max_iterations = {}; need >= 1", max_iterations);
  if (!(tolerance > 0 && tolerance < 1)) return fmt::format("tolerance = {}; need 0 < tolerance < 1", tolerance);
  if (!(gap_tolerance > 0)) return fmt::format("gap_tolerance = {}; need > 0", gap_tolerance);
  if (!(step_fraction > 0 && step_fraction < 1))
    return fmt::format("step_fraction = {}; need 0 < step_fraction < 1", step_fraction);
  if (threads < 0) return fmt::format("threads = {}; need >= 0", threads);
  return "";
}

void ValidateMapSmootherProblem(const MapSmootherProblem& p) {
  IDENT_REQUIRE(p.z.cols() >= 1, "z has no time steps (need T+1 >= 1 columns)");
  IDENT_REQUIRE(p.z.rows() >= 1, "z has no measurement rows");
  IDENT_REQUIRE(p.z.allFinite(), "z has a non-finite entry");
  const int T = p.T();
  IDENT_REQUIRE(p.H.size() == 1 || static_cast<int>(p.H.size()) == T + 1, "H has {} matrices; need 1 or T+1 = {}",
                p.H.size(), T + 1);
  const int n = p.state_dim(), nz = p.measurement_dim();
  IDENT_REQUIRE(n >= 1, "H has no columns (state dimension 0)");
  for (size_t t = 0; t < p.H.size(); ++t) {
    IDENT_REQUIRE(p.H[t].rows() == nz && p.H[t].cols() == n, "H[{}] is {}x{}; need {}x{} (z has {} rows)", t,
                  p.H[t].rows(), p.H[t].cols(), nz, n, nz);
    IDENT_REQUIRE(p.H[t].allFinite(), "H[{}] has a non-finite entry", t);
  }
  if (T > 0) {
    IDENT_REQUIRE(p.F.size() == 1 || static_cast<int>(p.F.size()) == T, "F has {} matrices; need 1 or T = {}",
                  p.F.size(), T);
    for (size_t t = 0; t < p.F.size(); ++t) {
      IDENT_REQUIRE(p.F[t].rows() == n && p.F[t].cols() == n, "F[{}] is {}x{}; need {}x{}", t, p.F[t].rows(),
                    p.F[t].cols(), n, n);
      IDENT_REQUIRE(p.F[t].allFinite(), "F[{}] has a non-finite entry", t);
    }
  }
  const size_t np = p.process.size();
  IDENT_REQUIRE(np == 1 || np == 2 || static_cast<int>(np) == T + 1,
                "process has {} penalties; need 1, 2 (initial, then all t) or T+1 = {}", np, T + 1);
  for (size_t t = 0; t < np; ++t)
    IDENT_REQUIRE(p.process[t].dim() == n, "process penalty {} has dimension {}; the state has {}", t,
                  p.process[t].dim(), n);
  IDENT_REQUIRE(p.measurement.size() == 1 || static_cast<int>(p.measurement.size()) == T + 1,
                "measurement has {} penalties; need 1 or T+1 = {}", p.measurement.size(), T + 1);
  for (size_t t = 0; t < p.measurement.size(); ++t)
    IDENT_REQUIRE(p.measurement[t].dim() == nz, "measurement penalty {} has dimension {}; z has {} rows", t,
                  p.measurement[t].dim(), nz);
}

double PrimalObjective(const MapSmootherProblem& p, const Eigen::MatrixXd& x, double domain_tolerance) {
  ValidateMapSmootherProblem(p);
  IDENT_REQUIRE(x.rows() == p.state_dim() && x.cols() == p.T() + 1, "x is {}x{}; need {}x{}", x.rows(), x.cols(),
                p.state_dim(), p.T() + 1);
  double sum = 0;
  Eigen::VectorXd w;
  for (int t = 0; t <= p.T(); ++t) {
    w = x.col(t);
    if (t > 0) w.noalias() -= p.Ft(t - 1) * x.col(t - 1);
    sum += p.ft(t).Value(w, domain_tolerance);
    sum += p.gt(t).Value(p.z.col(t) - p.Ht(t) * x.col(t), domain_tolerance);
  }
  return sum;
}

Eigen::MatrixXd DualStates(const MapSmootherProblem& p, const Eigen::MatrixXd& u) {
  ValidateMapSmootherProblem(p);
  IDENT_REQUIRE(u.rows() == p.measurement_dim() && u.cols() == p.T() + 1, "u is {}x{}; need {}x{}", u.rows(), u.cols(),
                p.measurement_dim(), p.T() + 1);
  const int T = p.T();
  Eigen::MatrixXd y(p.state_dim(), T + 1);
  y.col(T) = p.Ht(T).transpose() * u.col(T);  // y_T = H_T'u_T
  for (int t = T - 1; t >= 0; --t)            // y_t = F_t'y_{t+1} + H_t'u_t   [BCW Thm 2.5, A'y = H'u]
    y.col(t) = p.Ft(t).transpose() * y.col(t + 1) + p.Ht(t).transpose() * u.col(t);
  return y;
}

double DualObjective(const MapSmootherProblem& p, const Eigen::MatrixXd& u) {
  const Eigen::MatrixXd y = DualStates(p, u);
  double sum = 0;
  for (int t = 0; t <= p.T(); ++t)  // z'u - g*(u) - f*(y)   [BCW eq. (6)]
    sum += p.z.col(t).dot(u.col(t)) - p.gt(t).Conjugate(u.col(t)) - p.ft(t).Conjugate(y.col(t));
  return sum;
}

Eigen::MatrixXd StatesFromDual(const MapSmootherProblem& p, const Eigen::MatrixXd& y) {
  ValidateMapSmootherProblem(p);
  IDENT_REQUIRE(y.rows() == p.state_dim() && y.cols() == p.T() + 1, "y is {}x{}; need {}x{}", y.rows(), y.cols(),
                p.state_dim(), p.T() + 1);
  Eigen::MatrixXd x(p.state_dim(), p.T() + 1);
  for (int t = 0; t <= p.T(); ++t) {
    p.ft(t).ConjugateGradient(y.col(t), x.col(t));  // w_t in d f_t*(y_t)   [BCW sec. 3]
    if (t > 0) x.col(t) += p.Ft(t - 1) * x.col(t - 1);
  }
  return x;
}

MapSmootherResult SolveMapSmoother(const MapSmootherProblem& problem, const MapSmootherOptions& options) {
  ValidateMapSmootherProblem(problem);
  const std::string error = options.Validate();
  IDENT_REQUIRE(error.empty(), "MapSmootherOptions: {}", error);
  if (options.fast_path && internal::MapSmootherFastPathApplies(problem))
    return internal::SolveMapSmootherFastPath(problem, options);
  return internal::SolveMapSmootherInteriorPoint(problem, options);
}

}  // namespace ident
