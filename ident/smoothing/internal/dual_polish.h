// The dual polish of the MAP smoother's certificate (internal to ident/smoothing/; see
// ident/smoothing/internal/map_smoother_result.h, FinishMapSmootherResult).
#pragma once

#include <Eigen/Core>

#include "ident/smoothing/internal/map_smoother_result.h"

namespace ident::internal {

// rho = A'v - H'u, N xi = -rho with N = sum J'WJ (the Newton matrix of `dual`'s weights), v += W_f A xi,
// u -= W_g H xi, twice; a round that does not lower max |rho| is undone. v (n x (T+1), the process terms'
// dual values) and u (nz x (T+1)) in the data's unit. Returns max |rho|.
double PolishMapSmootherDual(const MapSmootherProblem& problem, const MapSmootherDualIterate& dual, Eigen::MatrixXd* v,
                             Eigen::MatrixXd* u);

}  // namespace ident::internal
