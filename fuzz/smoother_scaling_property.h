// Differential property of the MAP smoother: its answer does not depend on the data's unit or origin.
// Input: 1 byte state dimension n (1..2), 1 byte T+1 (2..33), 1 byte penalty choice, 4 bytes of penalty
// parameters, 1 byte scale exponent k, 2 bytes shift, 1 byte solver path, then T+1 measurements int8/8.
// For the problem P built from them:
//   - scaled: s = 2^k (k in -40..40, exact in binary), z' = s·z and every penalty ρ replaced by
//     s²·ρ(r/s) (Quadratic(C) unchanged, Huber(κ) → Huber(sκ), BoxMonitoring(lo, hi, M) →
//     BoxMonitoring(s·lo, s·hi, M), PiecewiseLinear(k, v) → PiecewiseLinear(s·k, s²·v)). The objective of
//     (P') at s·x is s² times that of (P) at x, so the smoother returns s·x̂ with the optimum s²·(P)* —
//     and, since it iterates in the data's own unit, the same iterates: the status, the states and the
//     objective agree to rounding (1e-12 relative);
//   - shifted (piecewise-linear measurement penalty): z' = z + d with the knots moved by d leaves every
//     residual's penalty unchanged: the same status and the same optimum, the two primal values apart
//     by at most the sum of their reported duality gaps.
// Holds if both hold whenever P converges; non-convergence of P itself is another property's business
// (tests/smoothing/feasible_problem_test.cc).
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>

#include <Eigen/Core>

#include "common/error.h"
#include "fuzz/fuzz_util.h"
#include "ident/smoothing/map_smoother.h"
#include "models/penalties.h"

namespace ident::fuzz {

struct ScalableSmootherProblem {
  MapSmootherProblem problem;
  models::Penalty::Kind process_kind, measurement_kind;
  double process_parameter = 0, measurement_parameter = 0;
  Eigen::Vector3d knots, values;  // the piecewise-linear measurement penalty
};

inline models::Penalty ScalablePenalty(models::Penalty::Kind kind, double parameter, int dim, double s,
                                       const Eigen::Vector3d& knots, const Eigen::Vector3d& values) {
  using models::Penalty;
  switch (kind) {
    case Penalty::Kind::kHuber:
      return Penalty::Huber(s * parameter, dim);
    case Penalty::Kind::kBoxMonitoring:
      return Penalty::BoxMonitoring(Eigen::VectorXd::Constant(dim, -s * parameter), Eigen::VectorXd::Constant(dim, s),
                                    Eigen::MatrixXd::Identity(dim, dim));
    case Penalty::Kind::kPiecewiseLinear:
      return Penalty::PiecewiseLinear(s * knots, s * s * values);
    default:
      return Penalty::Quadratic(parameter * Eigen::MatrixXd::Identity(dim, dim));
  }
}

// The problem scaled by s (and, for a piecewise-linear measurement penalty, shifted by d after scaling).
inline MapSmootherProblem ScaledSmootherProblem(const ScalableSmootherProblem& b, double s, double d) {
  MapSmootherProblem p = b.problem;
  const int n = p.state_dim();
  p.z = s * b.problem.z;
  p.z.array() += d;
  p.process = {models::Penalty::Quadratic(Eigen::MatrixXd::Identity(n, n)),
               ScalablePenalty(b.process_kind, b.process_parameter, n, s, b.knots, b.values)};
  models::Penalty g = ScalablePenalty(b.measurement_kind, b.measurement_parameter, 1, s, b.knots, b.values);
  if (d != 0) g = models::Penalty::PiecewiseLinear((s * b.knots).array() + d, s * s * b.values);
  p.measurement = {g};
  return p;
}

inline std::string SmootherScalingProperty(const std::uint8_t* data, std::size_t size) {
  using models::Penalty;
  ByteReader in(data, size);
  const int n = 1 + in.Byte() % 2, rows = 2 + in.Byte() % 32;
  const int choice = in.Byte();
  const double a = 0.25 + in.Byte() / 64.0, c = 0.25 + in.Byte() / 64.0;  // in [0.25, 4.25)
  const double lo = -(0.25 + in.Byte() / 32.0), hi = 0.25 + in.Byte() / 32.0;
  const int k = static_cast<int>(in.Byte() % 81) - 40;
  const int shift_raw = static_cast<std::int16_t>(in.Byte() | (in.Byte() << 8));
  const bool fast = in.Byte() & 1;
  ScalableSmootherProblem b;
  constexpr Penalty::Kind kProcess[] = {Penalty::Kind::kQuadratic, Penalty::Kind::kHuber,
                                        Penalty::Kind::kBoxMonitoring};
  constexpr Penalty::Kind kMeasurement[] = {Penalty::Kind::kQuadratic, Penalty::Kind::kHuber,
                                            Penalty::Kind::kBoxMonitoring, Penalty::Kind::kPiecewiseLinear};
  b.process_kind = kProcess[choice % 3];
  b.measurement_kind = kMeasurement[(choice / 3) % 4];
  b.process_parameter = a;
  b.measurement_parameter = c;
  b.knots = Eigen::Vector3d(lo, lo + (hi - lo) * (choice % 7 + 1) / 8.0, hi);
  b.values = Eigen::Vector3d(a * (b.knots(1) - lo), 0, c * (hi - b.knots(1)));
  MapSmootherProblem& p = b.problem;
  Eigen::MatrixXd F = 0.9 * Eigen::MatrixXd::Identity(n, n);
  if (n == 2) F(0, 1) = 0.25;
  p.F = {F};
  p.H = {Eigen::MatrixXd::Ones(1, n)};
  p.z.resize(1, rows);
  for (int t = 0; t < rows; ++t) p.z(0, t) = static_cast<std::int8_t>(in.Byte()) / 8.0;
  if (b.measurement_kind == Penalty::Kind::kPiecewiseLinear) {
    // Keep a known feasible point: z within the domain [lo, hi] of the residual at x = 0.
    for (int t = 0; t < rows; ++t) p.z(0, t) = lo + (hi - lo) * (0.05 + 0.9 * std::abs(std::sin(p.z(0, t) + t)));
  }
  const ScalableSmootherProblem& base = b;
  MapSmootherOptions o;
  o.fast_path = fast;
  MapSmootherResult r0;
  try {
    r0 = SolveMapSmoother(ScaledSmootherProblem(base, 1.0, 0.0), o);
  } catch (const InvalidArgument&) {
    return {};
  }
  if (r0.status != MapSmootherStatus::kConverged) return {};
  const double s = std::ldexp(1.0, k);
  const MapSmootherResult r1 = SolveMapSmoother(ScaledSmootherProblem(base, s, 0.0), o);
  if (r1.status != MapSmootherStatus::kConverged) return "the scaled problem converges as the original does";
  const double x_scale = r0.x.cwiseAbs().maxCoeff() + r0.w.cwiseAbs().maxCoeff() + p.z.cwiseAbs().maxCoeff();
  if (!((r1.x / s - r0.x).cwiseAbs().maxCoeff() <= 1e-12 * x_scale)) return "scaled states are s times the states";
  if (!(std::abs(r1.primal / (s * s) - r0.primal) <= 1e-12 * (1 + std::abs(r0.primal))))
    return "the scaled optimum is s^2 times the optimum";
  if (b.measurement_kind == Penalty::Kind::kPiecewiseLinear) {
    const double d = shift_raw / 4.0;
    const MapSmootherResult r2 = SolveMapSmoother(ScaledSmootherProblem(base, 1.0, d), o);
    // The shift moves the kinks of the residual's penalty off the binary grid, so the shifted problem may
    // stop at its precision limit (kStalled, with its certified gap) where the original converged.
    if (r2.status != MapSmootherStatus::kConverged && r2.status != MapSmootherStatus::kStalled)
      return "the shifted problem converges, or stalls at its precision limit, as the original converges (" +
             r2.message + ")";
    // Each primal value is within its own reported gap above the common optimum (the iteration may stop
    // at the precision limit with a gap above the tolerance).
    if (!(std::abs(r2.primal - r0.primal) <= std::abs(r0.gap) + std::abs(r2.gap) + 1e-9 * (1 + std::abs(r0.primal))))
      return "the shifted problem has the same optimum, within the reported gaps";
  }
  return {};
}

}  // namespace ident::fuzz
