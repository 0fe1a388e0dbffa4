// Grid Bayesian observer: the exact observer recursion of Henningsson & Åström (2006) on a grid,
// for 1 to 3 state dimensions.
//
//   (1) dynamics       f^d(x)  ∝ f_{k−1}(A⁻¹(x − B u))     cubic (Catmull–Rom) interpolation of the old
//                                                         grid, separable along lines of axis 0 when the
//                                                         map keeps them (A⁻¹ upper triangular, e.g. the
//                                                         double integrator's shear)
//   (2) process noise  f^dn    = f_N * f^d                 a Gaussian f_N is the lattice kernel with the
//                                                         exact covariance P_N (its spectrum, a lattice
//                                                         characteristic function,
//                                                         grid_observer_convolution.cc),
//                                                         computed once per spacing and P_N: a direct
//                                                         convolution when it has few taps, else an FFT
//                                                         (Eigen FFT, zero padded); any other log-concave
//                                                         f_N is sampled on the grid (FFT)
//   (3) measurement    f_k(x)  ∝ f_M(y, x) · f^dn(x)      pointwise product, in log space shifted by
//                                                         max log f_M (no underflow), renormalised; a
//                                                         reading c'x ∈ [lo, hi] with c along one axis
//                                                         weighs each node by the fraction of its cell
//                                                         inside the interval (the cut is exact to
//                                                         first order in the spacing)
//
// The grid follows the density: each step it must hold the image under x ↦ A x + B u of the previous
// density's support (nodes with f > support_level·max f), widened by noise_sigmas process-noise
// standard deviations. The spacing is kept while that box fits and fills at least 60 % of the grid, and
// the origin moves by B u plus whole cells, so an axis that A maps onto itself (a row e_i' of A) is
// carried node onto node without interpolation; otherwise the axis is re-gridded to the box plus 20 %.
// Discretisation error: O(Δ⁴) per step from the interpolation of smooth densities, O(Δ²) for the
// moments overall (node values, cut cells); GridRefinement (grid_refinement.h) checks the size.
//
// Read-outs: mean(), covariance() (sums over the grid), density() with axis(i) coordinates.
// Cost per step: O(N) for the dynamics and the reading, O(N · taps) or O(N log N) for the noise, N grid
// points; no allocation after construction.
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
  // Times the Gaussian noise kernel was built (once per new spacing or P_N), for benchmarks.
  long kernel_builds() const { return kernel_builds_; }

 private:
  StepReport PredictImpl(const models::LinearStateSpace& model, const Eigen::Ref<const Eigen::VectorXd>& u,
                         const LogDensity* log_noise);
  // The support box of the density: centre and half-width per axis of the nodes above support_level · max.
  void SupportBox(std::array<double, 3>& mid, std::array<double, 3>& half) const;
  // Places the grid over the box's image under x ↦ A x + B u (shift = B u), widened by the process noise,
  // keeping the spacing and whole-cell alignment when it can; false if that grid is beyond double range.
  bool MoveGrid(const models::LinearStateSpace& model, const Eigen::Ref<const Eigen::VectorXd>& shift,
                const std::array<double, 3>& mid, const std::array<double, 3>& half);
  // q ← the density p before the step at A⁻¹(x − B u) on the moved grid (eq. (1)), cubic interpolation
  // between the old grid's nodes (old_origin, old_spacing), zero outside the old grid.
  void PushForward(const Eigen::Ref<const Eigen::MatrixXd>& Ainv, const Eigen::Ref<const Eigen::VectorXd>& shift,
                   const std::array<double, 3>& old_origin, const std::array<double, 3>& old_spacing);
  // Fractional old-grid indices of the moved grid's nodes under eq. (1): f_j = f0_j + Σ_i G_ji k_i for node
  // indices k.
  struct OldIndexMap {
    std::array<double, 3> f0{};
    std::array<std::array<double, 3>, 3> G{};
  };
  // Lines along axis 0 of the old grid with their cubic weights (up to 4^(dim−1)).
  struct OldLines {
    std::array<const double*, 16> rows{};
    std::array<double, 16> weight{};
    int count = 0;
  };
  // The old lines whose weighted sum a new line along axis 0 (indices jl on axes 1 …) interpolates from;
  // none if the line maps outside the old grid.
  OldLines LinesFeeding(const OldIndexMap& map, const std::array<int, 3>& jl) const;
  // q on one line along axis 0 when lines map into lines: LinesFeeding, then a 1-D cubic along axis 0.
  void PushForwardLine(const OldIndexMap& map, int line);
  // out[j] += the cubic at old index j + a of the combined old lines (the same fraction for every node).
  void ShiftLine(const OldLines& old, double a, double* out);
  // out[j] = the cubic at old index a + b j of the combined old lines.
  void InterpolateLine(const OldLines& old, double a, double b, double* out) const;
  // The cubic over the 4^dim old nodes around node idx's image (any map); 0 outside the old grid.
  double InterpolateNode(const OldIndexMap& map, int idx) const;
  // q ← f_N * q (eq. (2)).
  void Convolve(const Eigen::MatrixXd& noise_cov, const LogDensity* log_noise);
  // Whether the cached Gaussian kernel is that of noise_cov on the current spacing.
  bool KernelMatches(const Eigen::MatrixXd& noise_cov) const;
  // q ← the direct convolution of q with the kernel's taps, zero outside the grid.
  void ConvolveTaps();
  // r's line `line` along axis 0 ← Σ_taps w · q(j − offset).
  void ConvolveTapsLine(int line);
  // q ← f_N * q by the FFT of the zero-padded grid: the Gaussian spectrum of noise_cov, or with log_noise
  // the transform of f_N sampled at the grid offsets.
  void ConvolveFft(const Eigen::MatrixXd& noise_cov, const LogDensity* log_noise);
  // kernel_ ← the transform of f_N sampled at the wrapped grid offsets of the padded grid, normalised.
  void SampledNoiseSpectrum(const LogDensity& log_noise);
  // The signed offset (index k, or k − np for the upper half) along axis i of padded flat index `flat`.
  int SignedPaddedIndex(int flat, int i) const;
  // The padded flat index of grid index idx.
  int PaddedIndex(int idx) const;
  // The lattice Gaussian kernel of noise_cov on the current spacing: its spectrum, and its taps if few.
  void BuildGaussianKernel(const Eigen::MatrixXd& noise_cov);
  // The lattice characteristic function of noise_cov on the padded grid (spectrum_).
  void BuildSpectrum(const Eigen::MatrixXd& noise_cov);
  // 1–2 states: the taps of a factorised lattice kernel with covariance noise_cov; false if not applicable
  // or more than max_taps.
  bool FactorisedTaps(const Eigen::MatrixXd& noise_cov, double max_taps);
  void FftLines(std::vector<std::complex<double>>& data, bool inverse, bool skip_padding);
  // Completes a step on q: normalise, moments, then q becomes the density; or, if q is not a finite
  // normalisable density with finite moments, the grid and the density stay as they were (kNumericalFailure).
  StepReport Commit();
  // Sum, mean and covariance of an unnormalised density v on the current grid; false if not finite or sum ≤ 0.
  bool Moments(const std::vector<double>& v, double& sum, Eigen::VectorXd& mean, Eigen::MatrixXd& cov) const;
  void NodeCoordinates(int index, Eigen::VectorXd& x) const;

  GridObserverOptions options_;
  int dim_ = 0, total_ = 0, padded_total_ = 0;
  std::array<int, 3> n_{1, 1, 1}, np_{1, 1, 1};
  std::array<double, 3> origin_{}, spacing_{1, 1, 1};
  std::array<double, 3> origin_saved_{}, spacing_saved_{};
  std::vector<double> p_, q_, r_;
  double max_p_ = 0;  // largest density value, for the support box
  // Gaussian kernel cache: valid for kernel_spacing_ and kernel_cov_ (dim × dim, row-major).
  bool kernel_valid_ = false, spectrum_valid_ = false;
  std::array<double, 3> kernel_spacing_{};
  std::array<double, 9> kernel_cov_{};
  std::vector<double> spectrum_;                // padded_total_ multipliers
  std::vector<std::array<int, 3>> tap_offset_;  // direct convolution taps (empty: use the FFT)
  std::vector<double> tap_weight_;
  int taps_ = 0;
  std::vector<double> line_factor_, axis_ds_, axis_diag_;
  long kernel_builds_ = 0;  // per-axis likelihood factors (reading along one axis)
  std::vector<std::complex<double>> buf_, line_in_, line_out_, kernel_;
  Eigen::FFT<double> fft_;
  Eigen::VectorXd mean_, x_, mean_new_;
  Eigen::MatrixXd cov_, cov_new_;
  models::LinearStateSpace model_;
  std::shared_ptr<const models::MeasurementFunction> measurement_;
};

}  // namespace ident
