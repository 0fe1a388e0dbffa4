// Shared data of the real-time tests: an ARX(2,2) stream with θ = (−1.5, 0.7, 1.0, 0.5), binary input,
// Gaussian noise σ = 0.1 and, optionally, gross outliers of ±5 in a given fraction of the samples.
#pragma once

#include <random>
#include <vector>

#include <Eigen/Core>

namespace ident::testing {

struct ArxSample {
  double y;
  Eigen::Vector4d z;
};

inline std::vector<ArxSample> ArxData(unsigned seed, int count, double outlier_fraction = 0) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0, 0.1);
  std::bernoulli_distribution coin, outlier(outlier_fraction);
  const Eigen::Vector4d theta(-1.5, 0.7, 1.0, 0.5);
  std::vector<ArxSample> data;
  double y1 = 0, y2 = 0, u1 = 1, u2 = -1;
  for (int t = 0; t < count; ++t) {
    const Eigen::Vector4d z(-y1, -y2, u1, u2);
    const double y = theta.dot(z) + noise(rng);
    const bool gross = outlier_fraction > 0 && outlier(rng);
    data.push_back({y + (gross ? (coin(rng) ? 5.0 : -5.0) : 0.0), z});
    y2 = y1, y1 = y, u2 = u1, u1 = coin(rng) ? 1.0 : -1.0;
  }
  return data;
}

}  // namespace ident::testing
