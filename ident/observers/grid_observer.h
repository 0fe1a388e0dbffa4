// Grid Bayesian observer: the exact observer recursion of Henningsson & Åström (2006) on a grid,
// for 1 to 3 state dimensions.
//
//   (1) dynamics       f^d(x)  ∝ f_{k−1}(A⁻¹(x − B u))     multilinear interpolation of the old grid
//   (2) process noise  f^dn    = f_N * f^d                 FFT convolution (Eigen FFT, zero padded); a
//                                                         Gaussian f_N multiplies the spectrum by a
//                                                         lattice characteristic function with the
//                                                         exact covariance P_N (grid_observer.cc), any
//                                                         other log-concave f_N is sampled on the grid
//   (3) measurement    f_k(x)  ∝ f_M(y, x) · f^dn(x)      pointwise product, in log space shifted by
//                                                         max log f_M (no underflow), renormalised
//
// The grid moves and resizes every step: an axis-aligned box around the image under x ↦ A x + B u of
// the previous density's support (nodes with f > 1e-12·max f), widened by noise_sigmas standard
// deviations of the process noise. Discretisation error: interpolation on a shifted grid smooths each
// axis by at most Δ_i²/4 of variance per step (Δ_i = spacing), and the density is represented to the
// grid spacing, so moments are accurate to O(Δ²); tests state their tolerances in units of Δ².
//
// Read-outs: mean(), covariance() (sums over the grid), density() with axis(i) coordinates.
// Cost per step: O(N log N) for N padded grid points; no allocation after construction.
//
// Example:
//   ident::GridObserver grid(Eigen::Vector2d::Zero(), Eigen::Matrix2d::Identity(), {.points = {128, 128}});
//   grid.Predict(model, u);           // eqs. (1)-(2)
//   grid.Correct(sensor, y);          // eq. (3)
//   Eigen::Vector2d m = grid.mean();
//
// [1] T. Henningsson, K. J. Åström, "Log-concave Observers", MTNS 2006.
#pragma once

#include <array>
#include <complex>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <unsupported/Eigen/FFT>

#include "common/step_report.h"
#include "ident/observers/state_observer.h"
#include "models/measurement.h"
#include "models/state_space.h"

namespace ident {

struct GridObserverOptions {
  std::vector<int> points = {128, 128};  // grid points per state dimension (1 to 3 dimensions), each ≥ 8
  double initial_sigmas = 8.0;           // initial box: mean ± initial_sigmas · sd of the prior
  double noise_sigmas = 6.0;             // box widened by this many process-noise sd per step
  double support_level = 1e-12;          // nodes with f < support_level · max f count as outside
  double min_half_width = 1e-6;          // lower limit of a box half-width
  int padding = 0;                       // FFT zero padding per axis; 0 = max(8, points/4)
  std::string Validate() const;          // "" if valid, else one line naming the option
};

class GridObserver {
 public:
  using LogDensity = std::function<double(const Eigen::Ref<const Eigen::VectorXd>&)>;

  // Prior N(m0, P0) sampled on the grid. Throws InvalidArgument on bad options or sizes.
  GridObserver(const Eigen::VectorXd& m0, const Eigen::MatrixXd& P0, const GridObserverOptions& options = {});
  // Convenience for Update(): a fixed model and measurement function.
  GridObserver(models::LinearStateSpace model, std::shared_ptr<const models::MeasurementFunction> measurement,
               const Eigen::VectorXd& m0, const Eigen::MatrixXd& P0, const GridObserverOptions& options = {});

  // Predict and Correct are each the whole step or nothing: kRejectedInvalid for a model or input
  // of the wrong size, non-finite entries, a singular A, or a reading that is not a possible output;
  // kNumericalFailure when the result would not be a finite, normalisable density with finite moments
  // (e.g. a grid beyond double range, a NaN likelihood, or a reading whose likelihood vanishes on
  // every node). In both cases the density, the grid and the moments are left bit-for-bit unchanged.
  //
  // Eqs. (1)-(2) with Gaussian process noise N(0, model.process_noise). A must be invertible.
  StepReport Predict(const models::LinearStateSpace& model, const Eigen::Ref<const Eigen::VectorXd>& u);
  // Eqs. (1)-(2) with any log-concave noise density (log f_N, need not be normalised); the box is
  // widened by noise_sigmas · sqrt(diag(model.process_noise)), so set process_noise to its covariance.
  StepReport Predict(const models::LinearStateSpace& model, const Eigen::Ref<const Eigen::VectorXd>& u,
                     const LogDensity& log_noise);
  // Eq. (3). kNumericalFailure (density unchanged) if f_M(y, ·) vanishes on every grid node with mass.
  StepReport Correct(const models::MeasurementFunction& measurement, double y);
  // Predict, then Correct if the prediction was taken (a failed Correct keeps the prediction).
  StepReport Update(const StateSpaceItem& item);

  const Eigen::VectorXd& mean() const { return mean_; }
  const Eigen::MatrixXd& covariance() const { return cov_; }
  int dim() const { return dim_; }
  int points(int i) const { return n_[i]; }
  double origin(int i) const { return origin_[i]; }
  double spacing(int i) const { return spacing_[i]; }
  double axis(int i, int j) const { return origin_[i] + j * spacing_[i]; }
  // Density values, dimension 0 fastest: index = j0 + n0 (j1 + n1 j2); integrates to 1 (Riemann sum).
  const std::vector<double>& density() const { return p_; }

 private:
  StepReport PredictImpl(const models::LinearStateSpace& model, const Eigen::Ref<const Eigen::VectorXd>& u,
                         const LogDensity* log_noise);
  // The support box of the density: centre and half-width per axis of the nodes above support_level · max.
  void SupportBox(std::array<double, 3>& mid, std::array<double, 3>& half) const;
  // Moves the grid onto the box's image under x ↦ A x + B u (shift = B u), widened by the process noise;
  // false if that grid is beyond double range.
  bool MoveGrid(const models::LinearStateSpace& model, const Eigen::Ref<const Eigen::VectorXd>& shift,
                const std::array<double, 3>& mid, const std::array<double, 3>& half);
  // p ← the density before the step at A⁻¹(x − B u) on the moved grid (eq. (1)), multilinear interpolation
  // between the old grid's nodes (old_origin, old_spacing).
  void PushForward(const Eigen::Ref<const Eigen::MatrixXd>& Ainv, const Eigen::Ref<const Eigen::VectorXd>& shift,
                   const std::array<double, 3>& old_origin, const std::array<double, 3>& old_spacing);
  void Convolve(const Eigen::MatrixXd& noise_cov, const LogDensity* log_noise);
  bool Normalise();
  bool UpdateMoments();  // false if a moment is not finite
  // Completes a step: normalise and update the moments, or restore the saved state (kNumericalFailure).
  StepReport Commit();
  void Save();
  void Restore();
  void NodeCoordinates(int index, Eigen::VectorXd& x) const;

  GridObserverOptions options_;
  int dim_ = 0, total_ = 0, padded_total_ = 0;
  std::array<int, 3> n_{1, 1, 1}, np_{1, 1, 1};
  std::array<double, 3> origin_{}, spacing_{1, 1, 1};
  std::vector<double> p_, q_, p_saved_;
  std::array<double, 3> origin_saved_{}, spacing_saved_{};
  Eigen::VectorXd mean_saved_;
  Eigen::MatrixXd cov_saved_;
  std::vector<std::complex<double>> buf_, line_in_, line_out_, kernel_;
  Eigen::FFT<double> fft_;
  Eigen::VectorXd mean_, x_;
  Eigen::MatrixXd cov_;
  models::LinearStateSpace model_;
  std::shared_ptr<const models::MeasurementFunction> measurement_;
};

}  // namespace ident
