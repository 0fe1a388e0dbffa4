// The seeded ARX(2,2) record on which the Cauchy estimator locks in (docs/explanation/karny-hangos-estimator.md),
// shared by the library test (lock_in_test.cc) and the command-line test (lock_in_cli_test.cc):
// the model of examples/kh_outlier_study.cc, Θ = (1.5, −0.7, 1.0, 0.5), binary input, σ = 0.1, and a
// fraction `outlier_rate` of innovation outliers of ±5.
#pragma once

#include <random>
#include <vector>

#include <Eigen/Core>

namespace ident::testing {

inline const Eigen::Vector4d kLockInTheta(1.5, -0.7, 1.0, 0.5);

struct LockInArx {
  std::vector<double> y;
  std::vector<Eigen::Vector4d> z;  // (y(t−1), y(t−2), u(t−1), u(t−2))
};

// n samples simulated, n − 2 regressions (the first two outputs only start the recursion).
inline LockInArx SimulateLockInArx(unsigned seed, int n, double outlier_rate = 0.1) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0, 0.1);
  std::uniform_real_distribution<double> uni(0, 1);
  std::vector<double> y(n, 0), u(n, 0);
  for (int t = 0; t < n; ++t) {
    u[t] = uni(rng) < 0.5 ? -1 : 1;
    const double e = g(rng);
    const double o = uni(rng) < outlier_rate ? (uni(rng) < 0.5 ? -5.0 : 5.0) : 0.0;
    y[t] = (t < 2 ? 0.0 : kLockInTheta.dot(Eigen::Vector4d(y[t - 1], y[t - 2], u[t - 1], u[t - 2]))) + e + o;
  }
  LockInArx d;
  for (int t = 2; t < n; ++t) {
    d.y.push_back(y[t]);
    d.z.emplace_back(y[t - 1], y[t - 2], u[t - 1], u[t - 2]);
  }
  return d;
}

}  // namespace ident::testing
