// The penalty terms of the MAP smoother's general path (internal to ident/smoothing/internal/interior_point.cc;
// see interior_point.h): the solver-side data of each distinct penalty in the data unit σ, and the process
// and measurement terms of (P) [ABP sec. 4] that refer to it.
#pragma once

#include <memory>

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include "ident/smoothing/map_smoother.h"

namespace ident::internal::interior_point {

using models::Penalty;
using models::PlqForm;

// Solver-side data of one distinct penalty.
struct Prepared {
  PlqForm scaled;                // the penalty's PLQ form in the data unit σ: p, b, lo, hi divided by σ
  const PlqForm* plq = nullptr;  // = &scaled
  int k = 0, m = 0;
  bool constant = false;    // no finite bound: K = M, W = B'M^-1 B fixed (its Newton block is precomputed)
  bool identity_B = false;  // B = I, b = 0, p = 0: v = p + B'u = u and B r - b = r
  Eigen::MatrixXd Kinv;     // constant case
  Eigen::MatrixXd W;        // constant case
  Eigen::VectorXd c0;       // constant case: at u = K^-1 (B r - b), p + B'u = c0 + W r with c0 = p - B'K^-1 b
  Eigen::MatrixXd K;        // dense case work
  Eigen::LLT<Eigen::MatrixXd> llt;
  Eigen::MatrixXd KinvB;  // dense case work (k x m)
};

struct Term {
  Prepared* prep;
  int offset;  // into the coordinate arrays (terms with a finite bound only; -1 for constant terms)
  int t;
  bool process;
  const double* F;  // F_{t-1} (process terms with t > 0), column-major n x n; else nullptr
  const double* H;  // H_t (measurement terms), column-major nz x n
};

// The solver-side data of the penalty in the data unit sigma; for a penalty without finite bounds, K^-1,
// W = B'K^-1 B and c0 = p - B'K^-1 b (M must be positive definite then).
std::unique_ptr<Prepared> PreparePenalty(const Penalty& pen, double sigma);

}  // namespace ident::internal::interior_point
