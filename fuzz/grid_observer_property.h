// Properties of the grid Bayesian observer (ident/observers/grid_observer.h) fed arbitrary models and readings.
// Input: 1 byte for the grid (dimension 1 + bit 0, so 1 or 2 states; 8 + (byte >> 1) % 9 points per
// dimension, i.e. 8..16: small grids, fast steps), then operations until the bytes run out, read as in
// observer_property.h: 1 byte op
//   even -> Predict with A (n×n), B (n×1), P_N = G G' (G n×n; or, if the op's bit 1 is set, P_N raw), u;
//   odd  -> Correct with c (n), a measurement kind (Gaussian, threshold, uniform quantiser, Laplace),
//           its parameter and y.
// Each number is a tame k/16 three times in four, else any bit pattern (NaN, ±Inf, subnormals, ±1e308).
// Holds if, after every operation:
//   updated     -> the grid is valid (finite origin, finite spacing > 0), the density is finite,
//                  non-negative and normalised (|Σ p · cell − 1| ≤ 1e-9), the mean is finite and inside
//                  the grid's box, the covariance finite with a non-negative diagonal;
//   not updated -> density, grid, mean and covariance are bit-for-bit unchanged.
// Predict and Correct must not throw (a throw is reported as a violation). A measurement whose
// parameters its constructor refuses (InvalidArgument) is skipped.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <exception>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "common/error.h"
#include "fuzz/fuzz_util.h"
#include "fuzz/observer_property.h"
#include "ident/observers/grid_observer.h"
#include "models/measurement.h"
#include "models/state_space.h"

namespace ident::fuzz {

namespace grid_detail {

struct Snapshot {
  std::vector<double> density;
  std::vector<double> origin, spacing;
  Eigen::VectorXd mean;
  Eigen::MatrixXd covariance;
  explicit Snapshot(const GridObserver& g) : density(g.density()), mean(g.mean()), covariance(g.covariance()) {
    for (int i = 0; i < g.dim(); ++i) {
      origin.push_back(g.origin(i));
      spacing.push_back(g.spacing(i));
    }
  }
  // Bit-for-bit (NaN never occurs in a valid state, so == is exact equality here).
  bool operator==(const Snapshot& o) const {
    return density == o.density && origin == o.origin && spacing == o.spacing && mean == o.mean &&
           covariance == o.covariance;
  }
};

// "" if the observer's state is a valid density with valid moments, else the property violated.
inline std::string CheckState(const GridObserver& g) {
  double cell = 1;
  for (int i = 0; i < g.dim(); ++i) {
    if (!std::isfinite(g.origin(i)) || !(g.spacing(i) > 0) || !std::isfinite(g.spacing(i))) {
      return "the grid has a finite origin and a finite spacing > 0";
    }
    cell *= g.spacing(i);
  }
  double mass = 0;
  for (double p : g.density()) {
    if (!(p >= 0) || !std::isfinite(p)) return "the density is finite and non-negative";
    mass += p * cell;
  }
  if (!(std::abs(mass - 1) <= 1e-9)) return "the density is normalised";
  if (!g.mean().allFinite() || !g.covariance().allFinite()) return "the mean and covariance are finite";
  for (int i = 0; i < g.dim(); ++i) {
    const double lo = g.axis(i, 0), hi = g.axis(i, g.points(i) - 1);
    const double tol = 1e-9 * std::max(std::abs(lo), std::abs(hi));
    if (!(g.mean()(i) >= lo - tol && g.mean()(i) <= hi + tol)) return "the mean lies inside the grid";
    if (!(g.covariance()(i, i) >= 0)) return "the covariance has a non-negative diagonal";
  }
  return {};
}

}  // namespace grid_detail

inline std::string GridObserverProperty(const std::uint8_t* data, std::size_t size) {
  using namespace observer_detail;
  ByteReader in(data, size);
  const std::uint8_t shape = in.Byte();
  const int n = 1 + (shape & 1);
  GridObserverOptions options;
  options.points.assign(n, 8 + (shape >> 1) % 9);
  GridObserver grid(Eigen::VectorXd::Zero(n), Eigen::MatrixXd::Identity(n, n), options);
  if (std::string bad = grid_detail::CheckState(grid); !bad.empty()) return "initial state: " + bad;
  models::LinearStateSpace model{Eigen::MatrixXd(n, n), Eigen::MatrixXd(n, 1), Eigen::MatrixXd(n, n)};
  Eigen::VectorXd u(1), c(n);
  while (in.remaining() > 0) {
    const std::uint8_t op = in.Byte();
    const grid_detail::Snapshot before(grid);
    StepReport report;
    try {
      if (op % 2 == 0) {
        ReadPredict(in, (op & 2) != 0, model, u);
        report = grid.Predict(model, u);
      } else {
        Fill(in, c);
        double y;
        const std::unique_ptr<models::ProjectedMeasurement> m = ReadMeasurement(in, c, y);
        if (!m) continue;  // refused at the boundary, as documented
        report = grid.Correct(*m, y);
      }
    } catch (const std::exception& e) {
      return std::string("Predict and Correct do not throw (threw: ") + e.what() + ")";
    }
    if (report.updated()) {
      if (std::string bad = grid_detail::CheckState(grid); !bad.empty()) return "after an updated step: " + bad;
    } else if (!(grid_detail::Snapshot(grid) == before)) {
      return "a step not taken leaves the state unchanged";
    }
  }
  return {};
}

}  // namespace ident::fuzz
