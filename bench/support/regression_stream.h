// A fixed, seeded regression stream for the per-update benchmarks (ld_rls_benchmark, kh_benchmark,
// weight_benchmark): y(t) = θ'z(t) + e(t) with θ and z(t) standard normal and n parameters, the noise
// e(t) either Gaussian or Cauchy, optionally with a fraction of gross ±outliers added. The stream is
// generated once (outside the timed loop); the same (n, options) always gives the same numbers.
//
//   const ident::bench::RegressionStream s(/*n=*/8, {.noise = ident::bench::Noise::kCauchy, .scale = 0.1,
//                                                    .outlier_fraction = 0.05, .outlier_size = 50});
//   for (int t = 0; t < s.length(); ++t) est.Update(s.y[t], s.z.col(t));
#pragma once

#include <random>

#include <Eigen/Core>

namespace ident::bench {

enum class Noise { kGaussian, kCauchy };

struct StreamOptions {
  Noise noise = Noise::kGaussian;
  double scale = 0.1;           // standard deviation (Gaussian) or scale (Cauchy) of e(t)
  double outlier_fraction = 0;  // probability that a sample gets an extra ±outlier_size
  double outlier_size = 50;
  int length = 4096;
  unsigned long long seed = 20261123;  // the stream for n parameters uses seed + n
};

struct RegressionStream {
  RegressionStream(int n, const StreamOptions& o = {}) : z(n, o.length), y(o.length) {
    std::mt19937_64 rng(o.seed + static_cast<unsigned long long>(n));
    std::normal_distribution<double> g;
    std::cauchy_distribution<double> c(0, o.scale);
    std::uniform_real_distribution<double> u(0, 1);
    Eigen::VectorXd theta(n);
    for (int i = 0; i < n; ++i) theta[i] = g(rng);
    for (int t = 0; t < o.length; ++t) {
      for (int i = 0; i < n; ++i) z(i, t) = g(rng);
      y[t] = theta.dot(z.col(t)) + (o.noise == Noise::kCauchy ? c(rng) : o.scale * g(rng));
      if (o.outlier_fraction > 0 && u(rng) < o.outlier_fraction)
        y[t] += u(rng) < 0.5 ? -o.outlier_size : o.outlier_size;
    }
  }
  int length() const { return static_cast<int>(y.size()); }

  Eigen::MatrixXd z;  // n x length, one regressor per column
  Eigen::VectorXd y;
};

}  // namespace ident::bench
