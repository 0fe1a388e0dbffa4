#include "models/state_space.h"

#include <cmath>

#include "common/dense_decompositions.h"
#include "common/error.h"

namespace ident::models {

LinearStateSpace LinearStateSpace::Make(Eigen::MatrixXd A, Eigen::MatrixXd B, Eigen::MatrixXd process_noise) {
  LinearStateSpace model{std::move(A), std::move(B), std::move(process_noise)};
  model.Validate();
  return model;
}

void LinearStateSpace::Validate() const {
  const auto n = A.rows();
  IDENT_REQUIRE(n >= 1 && A.cols() == n, "A is {}×{}; need a non-empty square matrix", A.rows(), A.cols());
  IDENT_REQUIRE(B.rows() == n, "B has {} rows; A has {}", B.rows(), n);
  IDENT_REQUIRE(process_noise.rows() == n && process_noise.cols() == n, "process_noise is {}×{}; need {}×{}",
                process_noise.rows(), process_noise.cols(), n, n);
  IDENT_REQUIRE(A.allFinite() && B.allFinite() && process_noise.allFinite(), "A, B and process_noise must be finite");
  IDENT_REQUIRE((process_noise - process_noise.transpose()).cwiseAbs().maxCoeff() <=
                    1e-12 * (1.0 + process_noise.cwiseAbs().maxCoeff()),
                "process_noise is not symmetric");
  const double min_eig = dense::SymmetricEigen(process_noise, Eigen::ComputeEigenvectors).eigenvalues().minCoeff();
  IDENT_REQUIRE(min_eig >= -1e-12 * (1.0 + process_noise.cwiseAbs().maxCoeff()),
                "process_noise has eigenvalue {}; need positive semidefinite", min_eig);
}

LinearStateSpace MemsAccelerometerDynamics(double h, double noise_intensity) {
  IDENT_REQUIRE(h > 0 && std::isfinite(h), "sampling period h = {}; need h > 0", h);
  IDENT_REQUIRE(noise_intensity >= 0 && std::isfinite(noise_intensity), "noise intensity sigma^2 = {}; need >= 0",
                noise_intensity);
  Eigen::MatrixXd A(2, 2), B(2, 1), P(2, 2);
  A << 1, h, 0, 1;  // [1, sec. II]
  B << 0.5 * h * h, h;
  P << h * h * h / 3, h * h / 2, h * h / 2, h;
  return LinearStateSpace::Make(A, B, noise_intensity * P);
}

}  // namespace ident::models
