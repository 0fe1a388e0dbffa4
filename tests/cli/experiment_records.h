// Simulated experiments for the tests of several experiments in one fit, comparison, order selection or
// prediction: y(t) = 1.5 y(t−1) − 0.7 y(t−2) + u(t−1) + 0.5 u(t−2) + e(t) around a level per experiment (the
// experiments differ in level, so a regressor straddling two of them is far off), and their least-squares
// regressors built from each experiment's own rows.
#pragma once

#include <string>
#include <vector>

#include <fmt/format.h>
#include <Eigen/Dense>

namespace ident::testing {

struct ExperimentRecord {
  std::vector<double> u, y;
};

inline ExperimentRecord SimulateExperiment(int n, unsigned seed, double level) {
  ExperimentRecord r;
  unsigned state = seed;
  auto uniform = [&state] {
    state = state * 1664525u + 1013904223u;
    return static_cast<double>(state >> 8) / 16777216.0 - 0.5;
  };
  double y1 = 0, y2 = 0, u1 = 0, u2 = 0;
  for (int t = 0; t < n; ++t) {
    const double u = uniform() > 0 ? 1.0 : -1.0;
    const double y = 1.5 * y1 - 0.7 * y2 + u1 + 0.5 * u2 + 0.1 * uniform();
    r.u.push_back(u);
    r.y.push_back(y + level);
    y2 = y1, y1 = y, u2 = u1, u1 = u;
  }
  return r;
}

inline std::string ExperimentsCsv(const std::vector<ExperimentRecord>& records, bool run_column) {
  std::string text = run_column ? "run,u,y\n" : "u,y\n";
  for (std::size_t k = 0; k < records.size(); ++k)
    for (std::size_t t = 0; t < records[k].y.size(); ++t)
      text += (run_column ? fmt::format("{},", k + 1) : "") +
              fmt::format("{:.17g},{:.17g}\n", records[k].u[t], records[k].y[t]);
  return text;
}

// z(t) = (−y(t−1), −y(t−2), u(t−1), u(t−2)) for t = 2 … n−1 of each experiment alone.
inline void ExperimentRegressors(const std::vector<ExperimentRecord>& records, Eigen::MatrixXd& Z, Eigen::VectorXd& Y) {
  std::vector<Eigen::RowVector4d> rows;
  std::vector<double> ys;
  for (const ExperimentRecord& r : records)
    for (std::size_t t = 2; t < r.y.size(); ++t) {
      rows.emplace_back(-r.y[t - 1], -r.y[t - 2], r.u[t - 1], r.u[t - 2]);
      ys.push_back(r.y[t]);
    }
  Z.resize(static_cast<Eigen::Index>(rows.size()), 4);
  Y.resize(static_cast<Eigen::Index>(rows.size()));
  for (std::size_t i = 0; i < rows.size(); ++i) {
    Z.row(static_cast<Eigen::Index>(i)) = rows[i];
    Y(static_cast<Eigen::Index>(i)) = ys[i];
  }
}

}  // namespace ident::testing
