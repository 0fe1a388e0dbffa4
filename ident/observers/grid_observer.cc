#include "ident/observers/grid_observer.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include <fmt/format.h>
#include <Eigen/Cholesky>
#include <Eigen/LU>

#include "common/error.h"
#include "models/measurement.h"

namespace ident {
namespace {

// At most 3 × 3 (1 to 3 states): Eigen keeps these on the stack.
using SmallMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 3, 3>;
using SmallVector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 3, 1>;

// Smallest m' ≥ m of the form 2^a 3^b 5^c (fast sizes for the FFT).
int NiceFftSize(int m) {
  for (int s = std::max(m, 1);; ++s) {
    int r = s;
    for (int f : {2, 3, 5})
      while (r % f == 0) r /= f;
    if (r == 1) return s;
  }
}

// Catmull–Rom cubic weights of the nodes base−1 … base+2 at fraction t ∈ [0, 1) past base: exact for
// quadratics, and exactly (0, 1, 0, 0) at t = 0, so a node-onto-node map interpolates nothing.
inline void CubicWeights(double t, double* w) {
  const double t2 = t * t, t3 = t2 * t;
  w[0] = 0.5 * (-t3 + 2 * t2 - t);
  w[1] = 0.5 * (3 * t3 - 5 * t2 + 2);
  w[2] = 0.5 * (-3 * t3 + 4 * t2 + t);
  w[3] = 0.5 * (t3 - t2);
}

// Spacing kept while the needed box fills at least this fraction of the grid; a new grid is the box
// widened by kGridSlack.
constexpr double kGridFill = 0.6;
constexpr double kGridSlack = 1.2;
// out[j] += Σ_g w[g] · in[j − g] for j in [lo, hi) and g < G: a direct convolution's taps on one source line (in
// points at the source line shifted by the first tap's offset). Built for AVX2/FMA too where GCC can dispatch.
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) && !defined(__SANITIZE_ADDRESS__)
#define IDENT_GRID_CLONES __attribute__((target_clones("arch=x86-64-v3", "default")))
#else
#define IDENT_GRID_CLONES
#endif
IDENT_GRID_CLONES void AddTaps3(double* __restrict out, const double* __restrict in, const double* w, int lo, int hi) {
  const double w0 = w[0], w1 = w[1], w2 = w[2];
  for (int j = lo; j < hi; ++j) out[j] += w0 * in[j] + w1 * in[j - 1] + w2 * in[j - 2];
}
IDENT_GRID_CLONES void AddTap(double* __restrict out, const double* __restrict in, double w, int lo, int hi) {
  for (int j = lo; j < hi; ++j) out[j] += w * in[j];
}

// Kernel entries below this fraction of the largest are dropped from a direct convolution.
constexpr double kTapLevel = 1e-14;

}  // namespace

std::string GridObserverOptions::Validate() const {
  if (points.empty() || points.size() > 3) return fmt::format("points has {} entries; need 1 to 3", points.size());
  for (int n : points)
    if (n < 8 || n > 4096) return fmt::format("points = {}; need 8 <= points <= 4096", n);
  if (!(initial_sigmas > 0)) return fmt::format("initial_sigmas = {}; need > 0", initial_sigmas);
  if (!(noise_sigmas >= 0)) return fmt::format("noise_sigmas = {}; need >= 0", noise_sigmas);
  if (!(support_level > 0 && support_level < 1))
    return fmt::format("support_level = {}; need in (0, 1)", support_level);
  if (!(min_half_width > 0)) return fmt::format("min_half_width = {}; need > 0", min_half_width);
  if (padding < 0) return fmt::format("padding = {}; need >= 0", padding);
  return "";
}

GridObserver::GridObserver(const Eigen::VectorXd& m0, const Eigen::MatrixXd& P0, const GridObserverOptions& options)
    : options_(options) {
  const std::string problem = options_.Validate();
  IDENT_REQUIRE(problem.empty(), "grid observer options: {}", problem);
  dim_ = static_cast<int>(options_.points.size());
  IDENT_REQUIRE(m0.size() == dim_ && m0.allFinite(), "m0 has {} entries; the grid has {} dimensions", m0.size(), dim_);
  IDENT_REQUIRE(P0.rows() == dim_ && P0.cols() == dim_ && P0.allFinite(), "P0 must be finite {}×{}", dim_, dim_);
  Eigen::LLT<Eigen::MatrixXd> llt(P0);
  IDENT_REQUIRE(llt.info() == Eigen::Success, "P0 is not positive definite");
  total_ = padded_total_ = 1;
  for (int i = 0; i < dim_; ++i) {
    n_[i] = options_.points[i];
    np_[i] = NiceFftSize(n_[i] + (options_.padding > 0 ? options_.padding : std::max(8, n_[i] / 4)));
    const double hw = std::max(options_.min_half_width, options_.initial_sigmas * std::sqrt(P0(i, i)));
    origin_[i] = m0(i) - hw;
    spacing_[i] = 2 * hw / (n_[i] - 1);
    total_ *= n_[i];
    padded_total_ *= np_[i];
  }
  origin_saved_ = origin_;
  spacing_saved_ = spacing_;
  p_.assign(total_, 0.0);
  q_.assign(total_, 0.0);
  r_.assign(total_, 0.0);
  buf_.assign(padded_total_, 0.0);
  kernel_.assign(padded_total_, 0.0);
  spectrum_.assign(padded_total_, 0.0);
  tap_offset_.assign(padded_total_, {0, 0, 0});
  tap_weight_.assign(padded_total_, 0.0);
  const int max_np = *std::max_element(np_.begin(), np_.end());
  line_in_.assign(max_np, 0.0);
  line_out_.assign(max_np, 0.0);
  line_factor_.assign(max_np, 0.0);
  axis_ds_.assign(3 * max_np, 0.0);
  axis_diag_.assign(3 * max_np, 0.0);
  mean_.resize(dim_);
  x_.resize(dim_);
  cov_.resize(dim_, dim_);
  mean_new_.resize(dim_);
  cov_new_.resize(dim_, dim_);
  const Eigen::MatrixXd Pinv = llt.solve(Eigen::MatrixXd::Identity(dim_, dim_));
  for (int idx = 0; idx < total_; ++idx) {
    NodeCoordinates(idx, x_);
    const Eigen::VectorXd d = x_ - m0;
    q_[idx] = std::exp(-0.5 * d.dot(Pinv * d));
  }
  IDENT_REQUIRE(Commit().updated(),
                "the prior N(m0, P0) cannot be represented on the grid in double precision (m0, P0 too large?)");
  for (int i = 0; i < dim_; ++i) {  // build the forward and inverse FFT plans now: steps allocate nothing
    fft_.fwd(line_out_.data(), line_in_.data(), np_[i]);
    fft_.inv(line_out_.data(), line_in_.data(), np_[i]);
  }
}

GridObserver::GridObserver(models::LinearStateSpace model,
                           std::shared_ptr<const models::MeasurementFunction> measurement, const Eigen::VectorXd& m0,
                           const Eigen::MatrixXd& P0, const GridObserverOptions& options)
    : GridObserver(m0, P0, options) {
  model.Validate();
  IDENT_REQUIRE(measurement != nullptr, "measurement must not be null");
  IDENT_REQUIRE(model.num_states() == dim_ && measurement->num_states() == dim_,
                "model ({}) and measurement ({}) must have {} states", model.num_states(), measurement->num_states(),
                dim_);
  model_ = std::move(model);
  measurement_ = std::move(measurement);
}

void GridObserver::NodeCoordinates(int index, Eigen::VectorXd& x) const {
  for (int i = 0; i < dim_; ++i) {
    const int j = index % n_[i];
    index /= n_[i];
    x(i) = origin_[i] + j * spacing_[i];
  }
}

StepReport GridObserver::Predict(const models::LinearStateSpace& model, const Eigen::Ref<const Eigen::VectorXd>& u) {
  return PredictImpl(model, u, nullptr);
}

StepReport GridObserver::Predict(const models::LinearStateSpace& model, const Eigen::Ref<const Eigen::VectorXd>& u,
                                 const LogDensity& log_noise) {
  IDENT_REQUIRE(static_cast<bool>(log_noise), "log_noise must be callable");
  return PredictImpl(model, u, &log_noise);
}

StepReport GridObserver::PredictImpl(const models::LinearStateSpace& model, const Eigen::Ref<const Eigen::VectorXd>& u,
                                     const LogDensity* log_noise) {
  if (!model.FitsStep(dim_, u) || !model.A.allFinite() || !model.B.allFinite() || !model.process_noise.allFinite()) {
    return {StepStatus::kRejectedInvalid};
  }
  // Small matrices live on the stack (at most 3 × 3): no heap allocation per step.
  Eigen::FullPivLU<SmallMatrix> lu(model.A);
  if (!lu.isInvertible()) return {StepStatus::kRejectedInvalid};
  const SmallMatrix Ainv = lu.inverse();
  if (!Ainv.allFinite()) return {StepStatus::kRejectedInvalid};  // singular to double precision
  SmallVector shift(dim_);
  shift.noalias() = model.B * u;
  if (!shift.allFinite()) return {StepStatus::kNumericalFailure};
  std::array<double, 3> mid{}, half{};
  SupportBox(mid, half);
  origin_saved_ = origin_;
  spacing_saved_ = spacing_;
  if (!MoveGrid(model, shift, mid, half)) {
    origin_ = origin_saved_;
    spacing_ = spacing_saved_;
    return {StepStatus::kNumericalFailure};
  }
  PushForward(Ainv, shift, origin_saved_, spacing_saved_);
  // (2): convolution with f_N.
  Convolve(model.process_noise, log_noise);
  return Commit();
}

void GridObserver::SupportBox(std::array<double, 3>& mid, std::array<double, 3>& half) const {
  // Nodes above support_level · max. No extra margin: a margin would compound from step to step.
  const double level = options_.support_level * max_p_;
  std::array<int, 3> lo{n_[0], n_[1], n_[2]}, hi{-1, -1, -1};
  const int n0 = n_[0], lines = total_ / n0;
  for (int line = 0; line < lines; ++line) {
    const double* row = p_.data() + static_cast<size_t>(line) * n0;
    int first = -1, last = -1;
    for (int j = 0; j < n0; ++j)
      if (row[j] > level) {
        if (first < 0) first = j;
        last = j;
      }
    if (first < 0) continue;
    lo[0] = std::min(lo[0], first);
    hi[0] = std::max(hi[0], last);
    int r = line;
    for (int i = 1; i < dim_; ++i) {
      const int j = r % n_[i];
      r /= n_[i];
      lo[i] = std::min(lo[i], j);
      hi[i] = std::max(hi[i], j);
    }
  }
  for (int i = 0; i < dim_; ++i) {
    if (hi[i] < 0) lo[i] = hi[i] = (n_[i] - 1) / 2;  // no node above the level (not reached for a density)
    const double a = origin_[i] + lo[i] * spacing_[i];
    const double b = origin_[i] + hi[i] * spacing_[i];
    mid[i] = 0.5 * (a + b);
    half[i] = 0.5 * (b - a);
  }
}

bool GridObserver::MoveGrid(const models::LinearStateSpace& model, const Eigen::Ref<const Eigen::VectorXd>& shift,
                            const std::array<double, 3>& mid, const std::array<double, 3>& half) {
  // Image of the box under x ↦ A x + B u, widened by the process noise.
  const Eigen::Map<const SmallVector> box_mid(mid.data(), dim_), box_half(half.data(), dim_);
  SmallVector new_mid(dim_), new_half(dim_);
  new_mid.noalias() = model.A * box_mid;
  new_mid += shift;
  new_half.noalias() = model.A.cwiseAbs() * box_half;
  for (int i = 0; i < dim_; ++i) {
    const double need =
        std::max(options_.min_half_width,
                 new_half(i) + options_.noise_sigmas * std::sqrt(std::max(0.0, model.process_noise(i, i))));
    const double extent = 0.5 * (n_[i] - 1) * spacing_[i];
    bool keep = need <= extent && need >= kGridFill * extent;
    if (keep) {
      // Whole cells from the image of the old origin along this axis: nodes map onto nodes when row i of A is e_i'.
      const double base = origin_[i] + shift(i);
      const double k = std::round((new_mid(i) - extent - base) / spacing_[i]);
      const double o = base + k * spacing_[i];
      keep = std::isfinite(o) && o <= new_mid(i) - need && o + 2 * extent >= new_mid(i) + need;
      if (keep) origin_[i] = o;
    }
    if (!keep) {
      const double hw = kGridSlack * need;
      origin_[i] = new_mid(i) - hw;
      spacing_[i] = 2 * hw / (n_[i] - 1);
    }
    // The box beyond double range (huge A, B u or noise): no representable grid.
    if (!std::isfinite(origin_[i]) || !(spacing_[i] > 0) || !std::isfinite(spacing_[i]) ||
        !std::isfinite(origin_[i] + (n_[i] - 1) * spacing_[i]))
      return false;
  }
  return true;
}

void GridObserver::PushForward(const Eigen::Ref<const Eigen::MatrixXd>& Ainv,
                               const Eigen::Ref<const Eigen::VectorXd>& shift, const std::array<double, 3>& old_origin,
                               const std::array<double, 3>& old_spacing) {
  // (1): f^d(x) = f_{k−1}(A⁻¹(x − B u)), cubic interpolation in fractional old indices f = f0 + Σ_i j_i G(:, i).
  SmallVector new_origin(dim_);
  for (int i = 0; i < dim_; ++i) new_origin(i) = origin_[i] - shift(i);
  SmallVector f0(dim_);
  f0.noalias() = Ainv * new_origin;
  SmallMatrix G = Ainv;
  for (int j = 0; j < dim_; ++j) {
    f0(j) = (f0(j) - old_origin[j]) / old_spacing[j];
    for (int i = 0; i < dim_; ++i) G(j, i) *= spacing_[i] / old_spacing[j];
  }
  const int n0 = n_[0], lines = total_ / n0;
  bool line_path = true;  // lines along axis 0 map into lines along axis 0 of the old grid
  for (int j = 1; j < dim_; ++j) line_path = line_path && G(j, 0) == 0;
  std::fill(q_.begin(), q_.end(), 0.0);
  if (line_path) {
    // Per line: up to 4^(dim−1) old lines with weights, then a 1-D cubic along axis 0.
    std::array<const double*, 16> rows{};
    std::array<double, 16> row_w{};
    for (int line = 0; line < lines; ++line) {
      std::array<int, 3> jl{0, 0, 0};
      int r = line;
      for (int i = 1; i < dim_; ++i) {
        jl[i] = r % n_[i];
        r /= n_[i];
      }
      int count = 1;
      rows[0] = p_.data();
      row_w[0] = 1;
      int stride = n0;
      for (int j = 1; j < dim_ && count > 0; ++j) {
        double f = f0(j);
        for (int i = 1; i < dim_; ++i) f += jl[i] * G(j, i);
        if (!(f > -2 && f < n_[j] + 1)) {
          count = 0;
          break;
        }
        const double fb = std::floor(f);
        double w[4];
        CubicWeights(f - fb, w);
        const int base = static_cast<int>(fb) - 1;
        int next = 0;
        std::array<const double*, 16> new_rows{};
        std::array<double, 16> new_w{};
        for (int c = 0; c < count; ++c)
          for (int k = 0; k < 4; ++k) {
            const int idx = base + k;
            if (w[k] == 0 || idx < 0 || idx >= n_[j]) continue;
            new_rows[next] = rows[c] + static_cast<ptrdiff_t>(idx) * stride;
            new_w[next++] = row_w[c] * w[k];
          }
        count = next;
        rows = new_rows;
        row_w = new_w;
        stride *= n_[j];
      }
      if (count == 0) continue;
      double* out = q_.data() + static_cast<size_t>(line) * n0;
      double a = f0(0);
      for (int i = 1; i < dim_; ++i) a += jl[i] * G(0, i);
      const double b = G(0, 0);
      if (std::abs(b - 1) * n0 <= 1e-9 && std::isfinite(a) && std::abs(a) < 4.0 * n0) {
        // Constant fraction along the line: the combined old line, then 4 shifted copies.
        double* tmp = r_.data();
        std::fill(tmp, tmp + n0, 0.0);
        for (int c = 0; c < count; ++c) {
          const double wc = row_w[c];
          const double* src = rows[c];
          for (int j = 0; j < n0; ++j) tmp[j] += wc * src[j];
        }
        const double fb = std::floor(a);
        double w[4];
        CubicWeights(a - fb, w);
        for (int k = 0; k < 4; ++k) {
          if (w[k] == 0) continue;
          const int off = static_cast<int>(fb) - 1 + k;  // old index = j + off
          const int lo = std::max(0, -off), hi = std::min(n0, n0 - off);
          const double wk = w[k];
          for (int j = lo; j < hi; ++j) out[j] += wk * tmp[j + off];
        }
      } else {
        for (int j0 = 0; j0 < n0; ++j0) {
          const double f = a + b * j0;
          if (!(f > -2 && f < n0 + 1)) continue;
          const double fb = std::floor(f);
          double w[4];
          CubicWeights(f - fb, w);
          const int base = static_cast<int>(fb) - 1;
          double v = 0;
          for (int k = 0; k < 4; ++k) {
            const int idx = base + k;
            if (idx < 0 || idx >= n0 || w[k] == 0) continue;
            double s = 0;
            for (int c = 0; c < count; ++c) s += row_w[c] * rows[c][idx];
            v += w[k] * s;
          }
          out[j0] = v;
        }
      }
    }
  } else {
    // Any map: per node, 4^dim old nodes.
    for (int idx = 0; idx < total_; ++idx) {
      std::array<double, 3> f{};
      int r = idx;
      for (int j = 0; j < dim_; ++j) f[j] = f0(j);
      for (int i = 0; i < dim_; ++i) {
        const int ji = r % n_[i];
        r /= n_[i];
        for (int j = 0; j < dim_; ++j) f[j] += ji * G(j, i);
      }
      std::array<std::array<double, 4>, 3> w{};
      std::array<int, 3> base{};
      bool inside = true;
      for (int j = 0; j < dim_; ++j) {
        if (!(f[j] > -2 && f[j] < n_[j] + 1)) {  // also NaN
          inside = false;
          break;
        }
        const double fb = std::floor(f[j]);
        CubicWeights(f[j] - fb, w[j].data());
        base[j] = static_cast<int>(fb) - 1;
      }
      if (!inside) continue;
      double v = 0;
      const int corners = 1 << (2 * dim_);
      for (int corner = 0; corner < corners; ++corner) {
        double weight = 1;
        int flat = 0, stride = 1;
        for (int j = 0; j < dim_; ++j) {
          const int k = (corner >> (2 * j)) & 3;
          const int id = base[j] + k;
          if (id < 0 || id >= n_[j]) {
            weight = 0;
            break;
          }
          weight *= w[j][k];
          flat += id * stride;
          stride *= n_[j];
        }
        if (weight != 0) v += weight * p_[flat];
      }
      q_[idx] = v;
    }
  }
  for (double& v : q_) v = std::max(0.0, v);  // the cubic's undershoot next to a cut (and a NaN) becomes 0
}

void GridObserver::FftLines(std::vector<std::complex<double>>& data, bool inverse, bool skip_padding) {
  // Lines along each axis of the padded array; with skip_padding, lines whose index along a later axis lies in
  // the zero padding are left out (zero before the forward transform, not needed after the inverse one).
  for (int step = 0; step < dim_; ++step) {
    const int axis = inverse ? dim_ - 1 - step : step;
    const int len = np_[axis];
    int stride = 1;
    for (int i = 0; i < axis; ++i) stride *= np_[i];
    const int lines = padded_total_ / len;
    for (int line = 0; line < lines; ++line) {
      const int start = (line % stride) + (line / stride) * stride * len;
      if (skip_padding) {
        bool padding = false;
        int r = start / (stride * len);
        for (int i = axis + 1; i < dim_ && !padding; ++i) {
          padding = r % np_[i] >= n_[i];
          r /= np_[i];
        }
        if (padding) continue;
      }
      for (int k = 0; k < len; ++k) line_in_[k] = data[start + k * stride];
      if (inverse)
        fft_.inv(line_out_.data(), line_in_.data(), len);
      else
        fft_.fwd(line_out_.data(), line_in_.data(), len);
      for (int k = 0; k < len; ++k) data[start + k * stride] = line_out_[k];
    }
  }
}

void GridObserver::BuildSpectrum(const Eigen::MatrixXd& noise_cov) {
  // A lattice version of the characteristic function exp(−½ ω'P_N ω). The continuous one jumps at the
  // Nyquist frequency when P_N is narrow against the grid, and that jump becomes a slowly decaying 1/x
  // tail in space. With s_i = (2/Δ_i) sin(ω_i Δ_i/2) (periodic) and d_i = cos(ω_i Δ_i/2) we use the exponent
  // −½[(D s)'P_N(D s) + Σ_i P_N,ii (1 − d_i²) s_i²]: smooth and periodic in ω, ≥ 0 since P_N ≥ 0, equal to
  // −½ω'P_N ω to second order, so the kernel has exactly the covariance P_N (for diagonal P_N it is the
  // lattice heat kernel).
  // Per axis and frequency index k: D s (in axis_ds_) and P_N,ii (1 − d²) s² (in axis_diag_).
  const int max_np = *std::max_element(np_.begin(), np_.begin() + dim_);
  for (int i = 0; i < dim_; ++i)
    for (int k = 0; k < np_[i]; ++k) {
      const int sk = k < (np_[i] + 1) / 2 ? k : k - np_[i];
      const double half_angle = std::numbers::pi * sk / np_[i];
      const double si = 2 * std::sin(half_angle) / spacing_[i], d = std::cos(half_angle);
      axis_ds_[i * max_np + k] = d * si;
      axis_diag_[i * max_np + k] = noise_cov(i, i) * (1 - d * d) * si * si;
    }
  for (int flat = 0; flat < padded_total_; ++flat) {
    std::array<double, 3> ds{};
    double quad = 0;
    int r = flat;
    for (int i = 0; i < dim_; ++i) {
      const int k = r % np_[i];
      r /= np_[i];
      ds[i] = axis_ds_[i * max_np + k];
      quad += axis_diag_[i * max_np + k];
    }
    for (int i = 0; i < dim_; ++i) {
      quad += ds[i] * noise_cov(i, i) * ds[i];
      for (int j = i + 1; j < dim_; ++j) quad += 2 * ds[i] * noise_cov(i, j) * ds[j];
    }
    spectrum_[flat] = std::exp(-0.5 * quad);
  }
  spectrum_valid_ = true;
}

bool GridObserver::FactorisedTaps(const Eigen::MatrixXd& noise_cov, double max_taps) {
  // 1 or 2 states: the kernel as the lattice heat kernel g of P_N,aa along the last axis a, times (2-D) the
  // conditional offset along axis 0: mean β k Δ_1/Δ_0 cells (β = P_N,01/P_N,11), variance
  // v = (P_N,00 − β P_N,01)/Δ_0², on the nearest 3 nodes with those two moments. Its covariance is P_N
  // exactly (E k1² = P_N,11/Δ_1², E k0 k1 = β E k1² Δ_1/Δ_0, Var k0 = v + β² E k1² Δ_1²/Δ_0²).
  // Not used when v > 1/4 cell² (3 nodes are too few): BuildSpectrum's kernel.
  const int a = dim_ - 1, na = np_[a];
  const double qa = noise_cov(a, a);
  const double beta = dim_ == 2 && qa > 0 ? noise_cov(0, 1) / qa : 0;
  const double v = dim_ == 2 ? std::max(0.0, noise_cov(0, 0) - beta * noise_cov(0, 1)) / (spacing_[0] * spacing_[0]) : 0;
  if (!(qa >= 0) || !(v <= 0.25) || !std::isfinite(beta)) return false;
  // g: inverse DFT of the lattice characteristic function exp(−2 P_N,aa sin²(π k/np)/Δ_a²).
  for (int k = 0; k < na; ++k) {
    const double sn = std::sin(std::numbers::pi * k / na);
    line_in_[k] = std::exp(-2 * qa * sn * sn / (spacing_[a] * spacing_[a]));
  }
  fft_.inv(line_out_.data(), line_in_.data(), na);
  double max_g = 0;
  for (int k = 0; k < na; ++k) max_g = std::max(max_g, std::abs(line_out_[k].real()));
  if (!(max_g > 0)) return false;
  taps_ = 0;
  for (int k = 0; k < na; ++k) {
    const int off = k < (na + 1) / 2 ? k : k - na;
    const double g = line_out_[k].real();
    if (!(std::abs(g) > kTapLevel * max_g) || std::abs(off) >= n_[a]) continue;
    if (dim_ == 1) {
      if (taps_ + 1 > max_taps) return false;
      tap_offset_[taps_] = {off, 0, 0};
      tap_weight_[taps_++] = g;
      continue;
    }
    const double r = beta * off * spacing_[1] / spacing_[0];
    const double s0 = std::round(r), mu = r - s0;
    const double w[3] = {0.5 * (v + mu * mu - mu), 1 - v - mu * mu, 0.5 * (v + mu * mu + mu)};
    for (int d = -1; d <= 1; ++d) {
      const double o0 = s0 + d;
      if (w[d + 1] == 0 || !(std::abs(o0) < n_[0])) continue;
      if (taps_ + 1 > max_taps) return false;
      tap_offset_[taps_] = {static_cast<int>(o0), off, 0};
      tap_weight_[taps_++] = g * w[d + 1];
    }
  }
  return taps_ > 0;
}

void GridObserver::BuildGaussianKernel(const Eigen::MatrixXd& noise_cov) {
  auto signed_index = [&](int flat, int i) {
    int r = flat;
    for (int a = 0; a < i; ++a) r /= np_[a];
    const int k = r % np_[i];
    return k < (np_[i] + 1) / 2 ? k : k - np_[i];
  };
  double log_cost = 0;
  for (int i = 0; i < dim_; ++i) log_cost += std::log2(static_cast<double>(np_[i]));
  // A tap costs one multiply-add per node; the FFTs (forward and inverse, strided lines) about 24 per node
  // and log2 of the padded size (measured with bench/observers_benchmark).
  const double max_taps = 24.0 * padded_total_ * log_cost / total_;
  spectrum_valid_ = false;
  kernel_valid_ = true;
  ++kernel_builds_;
  kernel_spacing_ = spacing_;
  for (int i = 0; i < dim_; ++i)
    for (int j = 0; j < dim_; ++j) kernel_cov_[3 * i + j] = noise_cov(i, j);
  if (dim_ <= 2 && FactorisedTaps(noise_cov, max_taps)) return;
  BuildSpectrum(noise_cov);
  // The kernel in space; a direct convolution when its taps above kTapLevel · max cost less than the FFTs.
  for (int flat = 0; flat < padded_total_; ++flat) buf_[flat] = spectrum_[flat];
  FftLines(buf_, true, false);
  double max_k = 0;
  for (const auto& v : buf_) max_k = std::max(max_k, std::abs(v.real()));
  taps_ = 0;
  for (int flat = 0; flat < padded_total_ && taps_ >= 0; ++flat) {
    const double v = buf_[flat].real();
    if (!(std::abs(v) > kTapLevel * max_k)) continue;
    std::array<int, 3> off{0, 0, 0};
    bool reachable = true;
    for (int i = 0; i < dim_; ++i) {
      off[i] = signed_index(flat, i);
      reachable = reachable && std::abs(off[i]) < n_[i];
    }
    if (!reachable) continue;  // cannot move mass within the grid
    if (taps_ + 1 > max_taps) {
      taps_ = -1;
      break;
    }
    tap_offset_[taps_] = off;
    tap_weight_[taps_++] = v;
  }
  if (taps_ < 0) taps_ = 0;  // the FFT
  else if (taps_ == 0) {     // no tap (not reached: the kernel sums to 1): the identity
    tap_offset_[0] = {0, 0, 0};
    tap_weight_[0] = 1;
    taps_ = 1;
  }
}

void GridObserver::Convolve(const Eigen::MatrixXd& noise_cov, const LogDensity* log_noise) {
  if (log_noise == nullptr) {
    bool valid = kernel_valid_;
    for (int i = 0; i < dim_ && valid; ++i) {
      valid = kernel_spacing_[i] == spacing_[i];
      for (int j = 0; j < dim_; ++j) valid = valid && kernel_cov_[3 * i + j] == noise_cov(i, j);
    }
    if (!valid) BuildGaussianKernel(noise_cov);
    if (taps_ == 1 && tap_weight_[0] == 1 && tap_offset_[0] == std::array<int, 3>{0, 0, 0}) return;
    if (taps_ > 0) {
      // Direct: out(j) = Σ_taps w · in(j − offset), zero outside the grid; per output line along axis 0, every tap.
      const int n0 = n_[0], lines = total_ / n0;
      for (int line = 0; line < lines; ++line) {
        std::array<int, 3> jl{0, 0, 0};
        int r = line;
        for (int i = 1; i < dim_; ++i) {
          jl[i] = r % n_[i];
          r /= n_[i];
        }
        double* __restrict out = r_.data() + static_cast<size_t>(line) * n0;
        std::fill(out, out + n0, 0.0);
        for (int t = 0; t < taps_;) {
          const auto& off = tap_offset_[t];
          // Taps t, t+1, t+2 on the same source line at consecutive offsets along axis 0: one fused pass.
          const bool three = t + 2 < taps_ && tap_offset_[t + 1][0] == off[0] + 1 &&
                             tap_offset_[t + 2][0] == off[0] + 2 && tap_offset_[t + 1][1] == off[1] &&
                             tap_offset_[t + 2][1] == off[1] && tap_offset_[t + 1][2] == off[2] &&
                             tap_offset_[t + 2][2] == off[2];
          const int group = three ? 3 : 1;
          int src_line = 0, stride = 1;
          bool inside = true;
          for (int i = 1; i < dim_; ++i) {
            const int j = jl[i] - off[i];
            inside = inside && j >= 0 && j < n_[i];
            src_line += j * stride;
            stride *= n_[i];
          }
          if (inside) {
            const double* line_in = q_.data() + static_cast<size_t>(src_line) * n0;
            // Output j reads line_in[j − off0 − g]; valid for 0 ≤ j − off0 − g < n0.
            const int lo = std::max(0, off[0] + group - 1), hi = std::min(n0, n0 + off[0]);
            if (three && lo < hi) {
              AddTaps3(out, line_in - off[0], &tap_weight_[t], lo, hi);
              for (int g = 0; g < 3; ++g) {  // the ends where only some of the three are inside
                const int glo = std::max(0, off[0] + g), ghi = std::min(n0, n0 + off[0] + g);
                AddTap(out, line_in - off[0] - g, tap_weight_[t + g], glo, std::min(ghi, lo));
                AddTap(out, line_in - off[0] - g, tap_weight_[t + g], std::max(glo, hi), ghi);
              }
            } else {
              for (int g = 0; g < group; ++g) {
                const int glo = std::max(0, off[0] + g), ghi = std::min(n0, n0 + off[0] + g);
                AddTap(out, line_in - off[0] - g, tap_weight_[t + g], glo, ghi);
              }
            }
          }
          t += group;
        }
      }
      for (int idx = 0; idx < total_; ++idx) q_[idx] = std::max(0.0, r_[idx]);
      return;
    }
  }
  auto padded_index = [&](int idx) {
    int flat = 0, stride = 1;
    for (int i = 0; i < dim_; ++i) {
      flat += (idx % n_[i]) * stride;
      idx /= n_[i];
      stride *= np_[i];
    }
    return flat;
  };
  std::fill(buf_.begin(), buf_.end(), 0.0);
  for (int idx = 0; idx < total_; ++idx) buf_[padded_index(idx)] = q_[idx];
  FftLines(buf_, false, true);
  if (log_noise == nullptr) {
    if (!spectrum_valid_) BuildSpectrum(noise_cov);
    for (int flat = 0; flat < padded_total_; ++flat) buf_[flat] *= spectrum_[flat];
  } else {
    // Any density: sample f_N at the grid offsets (wrapped), normalise, transform, multiply.
    auto signed_index = [&](int flat, int i) {
      int r = flat;
      for (int a = 0; a < i; ++a) r /= np_[a];
      const int k = r % np_[i];
      return k < (np_[i] + 1) / 2 ? k : k - np_[i];
    };
    double max_log = -std::numeric_limits<double>::infinity();
    for (int flat = 0; flat < padded_total_; ++flat) {
      for (int i = 0; i < dim_; ++i) x_(i) = signed_index(flat, i) * spacing_[i];
      const double l = (*log_noise)(x_);
      kernel_[flat] = l;
      max_log = std::max(max_log, l);
    }
    double sum = 0;
    for (auto& k : kernel_) {
      k = std::exp(k.real() - max_log);
      sum += k.real();
    }
    for (auto& k : kernel_) k /= sum;
    FftLines(kernel_, false, false);
    for (int flat = 0; flat < padded_total_; ++flat) buf_[flat] *= kernel_[flat];
  }
  FftLines(buf_, true, true);
  for (int idx = 0; idx < total_; ++idx) q_[idx] = std::max(0.0, buf_[padded_index(idx)].real());
}

bool GridObserver::Moments(const std::vector<double>& v, double& sum, Eigen::VectorXd& mean,
                           Eigen::MatrixXd& cov) const {
  // One pass in index units centred on the grid: S = Σ v, S_i = Σ v t_i, S_ij = Σ v t_i t_j.
  const int n0 = n_[0], lines = total_ / n0;
  const double c0 = 0.5 * (n0 - 1);
  double S = 0;
  std::array<double, 3> Si{};
  std::array<std::array<double, 3>, 3> Sij{};
  for (int line = 0; line < lines; ++line) {
    const double* row = v.data() + static_cast<size_t>(line) * n0;
    double s0 = 0, s1 = 0, s2 = 0;
    for (int j = 0; j < n0; ++j) {
      const double a = row[j], t = j - c0;
      s0 += a;
      s1 += a * t;
      s2 += a * t * t;
    }
    if (s0 == 0) continue;
    std::array<double, 3> t{0, 0, 0};
    int r = line;
    for (int i = 1; i < dim_; ++i) {
      t[i] = r % n_[i] - 0.5 * (n_[i] - 1);
      r /= n_[i];
    }
    S += s0;
    Si[0] += s1;
    Sij[0][0] += s2;
    for (int i = 1; i < dim_; ++i) {
      Si[i] += s0 * t[i];
      Sij[0][i] += s1 * t[i];
      for (int j = i; j < dim_; ++j) Sij[i][j] += s0 * t[i] * t[j];
    }
  }
  sum = S;
  if (!(S > 0) || !std::isfinite(S)) return false;
  for (int i = 0; i < dim_; ++i) {
    const double mi = Si[i] / S;
    mean(i) = origin_[i] + (0.5 * (n_[i] - 1) + mi) * spacing_[i];
    for (int j = i; j < dim_; ++j) {
      const double mj = Si[j] / S;
      double c = (Sij[i][j] / S - mi * mj) * spacing_[i] * spacing_[j];
      if (i == j) c = std::max(0.0, c);
      cov(i, j) = cov(j, i) = c;
    }
  }
  return mean.allFinite() && cov.allFinite();
}

StepReport GridObserver::Commit() {
  double sum = 0, cell = 1;
  for (int i = 0; i < dim_; ++i) cell *= spacing_[i];
  bool ok = std::isfinite(cell) && cell >= std::numeric_limits<double>::min() && Moments(q_, sum, mean_new_, cov_new_);
  double scale = 0, max_q = 0;
  if (ok) {
    scale = 1.0 / (sum * cell);
    ok = scale > 0 && std::isfinite(scale);
  }
  if (ok) {
    for (double& v : q_) {
      v *= scale;
      max_q = std::max(max_q, v);
    }
    ok = std::isfinite(max_q) && max_q > 0;
  }
  if (!ok) {
    origin_ = origin_saved_;
    spacing_ = spacing_saved_;
    return {StepStatus::kNumericalFailure};
  }
  p_.swap(q_);
  max_p_ = max_q;
  mean_ = mean_new_;
  cov_ = cov_new_;
  return {StepStatus::kUpdated};
}

StepReport GridObserver::Correct(const models::MeasurementFunction& measurement, double y) {
  if (measurement.num_states() != dim_ || !measurement.IsValidOutput(y)) return {StepStatus::kRejectedInvalid};
  origin_saved_ = origin_;
  spacing_saved_ = spacing_;
  const auto* projected = dynamic_cast<const models::ProjectedMeasurement*>(&measurement);
  int axis = -1;
  if (projected != nullptr) {
    int nonzero = 0;
    for (int i = 0; i < dim_; ++i)
      if (projected->c()(i) != 0) {
        ++nonzero;
        axis = i;
      }
    if (nonzero != 1) axis = -1;
  }
  if (axis >= 0) {
    // f_M depends on x_axis only: one factor per node of that axis.
    const double ci = projected->c()(axis), d = spacing_[axis];
    int stride = 1;
    for (int i = 0; i < axis; ++i) stride *= n_[i];
    const int na = n_[axis];
    auto axis_index = [&](int idx) { return (idx / stride) % na; };
    const auto* interval = dynamic_cast<const models::IntervalMeasurement*>(projected);
    if (interval != nullptr) {
      // Fraction of each cell [x − Δ/2, x + Δ/2] inside the reading's interval of x_axis.
      const auto [lo, hi] = interval->Interval(y);
      if (std::isnan(lo) || std::isnan(hi)) return {StepStatus::kNumericalFailure};
      const double a = ci > 0 ? lo / ci : hi / ci, b = ci > 0 ? hi / ci : lo / ci;
      for (int j = 0; j < na; ++j) {
        const double x = origin_[axis] + j * d;
        const double overlap = std::min(b, x + 0.5 * d) - std::max(a, x - 0.5 * d);
        line_factor_[j] = overlap > 0 ? std::min(1.0, overlap / d) : 0.0;
      }
    } else {
      // Which nodes of the axis carry mass.
      std::fill(line_factor_.begin(), line_factor_.begin() + na, 0.0);
      for (int idx = 0; idx < total_; ++idx)
        if (p_[idx] > 0) line_factor_[axis_index(idx)] = 1;
      double max_log = -std::numeric_limits<double>::infinity();
      for (int j = 0; j < na; ++j) {
        if (line_factor_[j] == 0) {
          line_factor_[j] = -std::numeric_limits<double>::infinity();
          continue;
        }
        const double l = projected->LogLikelihoodScalar(y, ci * (origin_[axis] + j * d));
        if (std::isnan(l)) return {StepStatus::kNumericalFailure};  // density unchanged
        line_factor_[j] = l;
        max_log = std::max(max_log, l);
      }
      if (!std::isfinite(max_log)) return {StepStatus::kNumericalFailure};  // density unchanged
      for (int j = 0; j < na; ++j) line_factor_[j] = std::exp(line_factor_[j] - max_log);
    }
    if (axis == 0) {
      const int lines = total_ / na;
      for (int line = 0; line < lines; ++line) {
        const double* in = p_.data() + static_cast<size_t>(line) * na;
        double* out = q_.data() + static_cast<size_t>(line) * na;
        for (int j = 0; j < na; ++j) out[j] = in[j] * line_factor_[j];
      }
    } else {
      for (int idx = 0; idx < total_; ++idx) q_[idx] = p_[idx] * line_factor_[axis_index(idx)];
    }
    return Commit();
  }
  // Any f_M: q = log f_M(y, x) on nodes with mass, shifted by its maximum before exp.
  double max_log = -std::numeric_limits<double>::infinity();
  for (int idx = 0; idx < total_; ++idx) {
    if (p_[idx] == 0) {
      q_[idx] = -std::numeric_limits<double>::infinity();
      continue;
    }
    NodeCoordinates(idx, x_);
    q_[idx] = measurement.LogLikelihood(y, x_);
    if (std::isnan(q_[idx])) return {StepStatus::kNumericalFailure};  // density unchanged
    max_log = std::max(max_log, q_[idx]);
  }
  if (!std::isfinite(max_log)) return {StepStatus::kNumericalFailure};  // density unchanged
  for (int idx = 0; idx < total_; ++idx) q_[idx] = p_[idx] * std::exp(q_[idx] - max_log);
  return Commit();
}

StepReport GridObserver::Update(const StateSpaceItem& item) {
  IDENT_REQUIRE(measurement_ != nullptr, "GridObserver::Update needs the constructor that takes a model");
  const StepReport predicted = Predict(model_, item.u);
  if (!predicted.updated()) return predicted;
  return Correct(*measurement_, item.y);
}

}  // namespace ident
