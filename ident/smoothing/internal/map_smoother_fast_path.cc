#include "ident/smoothing/internal/map_smoother_fast_path.h"

#include <cmath>

#include "ident/smoothing/internal/map_smoother_fast_path_passes.h"
#include "ident/smoothing/internal/map_smoother_fast_path_solver.h"

namespace ident::internal {
namespace {

using models::Penalty;
using models::PlqForm;

bool HasFiniteBound(const PlqForm& f) { return f.lo.array().isFinite().any() || f.hi.array().isFinite().any(); }

// Scalar identity-B term with both bounds finite: rho(r) = sup_{lo <= u <= hi} { u r - 1/2 m u^2 }.
bool IsScalarBoxTerm(const Penalty& g) {
  const PlqForm& f = g.plq();
  return g.dim() == 1 && f.rows() == 1 && f.B(0, 0) == 1.0 && f.b(0) == 0.0 && f.p(0) == 0.0 &&
         std::isfinite(f.lo(0)) && std::isfinite(f.hi(0)) && f.M(0, 0) >= 0.0;
}

}  // namespace

bool MapSmootherFastPathApplies(const MapSmootherProblem& p) {
  const int n = p.state_dim();
  if (n < 1 || n > 4 || p.measurement_dim() != 1) return false;
  for (const Penalty& f : p.process)
    if (HasFiniteBound(f.plq())) return false;
  for (const Penalty& g : p.measurement)
    if (!IsScalarBoxTerm(g)) return false;
  return true;
}

MapSmootherResult SolveMapSmootherFastPath(const MapSmootherProblem& p, const MapSmootherOptions& o) {
  switch (p.state_dim()) {
    case 1:
      return fast_path::FastSolver<1>(p, o).Run();
    case 2:
      return fast_path::FastSolver<2>(p, o).Run();
    case 3:
      return fast_path::FastSolver<3>(p, o).Run();
    default:
      return fast_path::FastSolver<4>(p, o).Run();
  }
}

}  // namespace ident::internal
