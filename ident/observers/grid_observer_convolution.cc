// The process-noise step (2) of the grid observer (grid_observer.h): the convolution with f_N, by a lattice
// Gaussian kernel's taps or spectrum, or by the FFT of any sampled log-concave density.
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "ident/linalg/internal/simd_clones.h"
#include "ident/observers/grid_observer.h"

namespace ident {
namespace {

// out[j] += Σ_g w[g] · in[j − g] for j in [lo, hi) and g < G: a direct convolution's taps on one source line (in
// points at the source line shifted by the first tap's offset).
IDENT_SIMD_CLONES void AddTaps3(double* __restrict out, const double* __restrict in, const double* w, int lo, int hi) {
  const double w0 = w[0], w1 = w[1], w2 = w[2];
  for (int j = lo; j < hi; ++j) out[j] += w0 * in[j] + w1 * in[j - 1] + w2 * in[j - 2];
}
IDENT_SIMD_CLONES void AddTap(double* __restrict out, const double* __restrict in, double w, int lo, int hi) {
  for (int j = lo; j < hi; ++j) out[j] += w * in[j];
}

// Kernel entries below this fraction of the largest are dropped from a direct convolution.
constexpr double kTapLevel = 1e-14;

}  // namespace

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
  const double v =
      dim_ == 2 ? std::max(0.0, noise_cov(0, 0) - beta * noise_cov(0, 1)) / (spacing_[0] * spacing_[0]) : 0;
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
      off[i] = SignedPaddedIndex(flat, i);
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
  if (taps_ < 0)
    taps_ = 0;            // the FFT
  else if (taps_ == 0) {  // no tap (not reached: the kernel sums to 1): the identity
    tap_offset_[0] = {0, 0, 0};
    tap_weight_[0] = 1;
    taps_ = 1;
  }
}

int GridObserver::SignedPaddedIndex(int flat, int i) const {
  int r = flat;
  for (int a = 0; a < i; ++a) r /= np_[a];
  const int k = r % np_[i];
  return k < (np_[i] + 1) / 2 ? k : k - np_[i];
}

int GridObserver::PaddedIndex(int idx) const {
  int flat = 0, stride = 1;
  for (int i = 0; i < dim_; ++i) {
    flat += (idx % n_[i]) * stride;
    idx /= n_[i];
    stride *= np_[i];
  }
  return flat;
}

void GridObserver::Convolve(const Eigen::MatrixXd& noise_cov, const LogDensity* log_noise) {
  if (log_noise == nullptr) {
    if (!KernelMatches(noise_cov)) BuildGaussianKernel(noise_cov);
    if (taps_ == 1 && tap_weight_[0] == 1 && tap_offset_[0] == std::array<int, 3>{0, 0, 0}) return;
    if (taps_ > 0) {
      ConvolveTaps();
      return;
    }
  }
  ConvolveFft(noise_cov, log_noise);
}

bool GridObserver::KernelMatches(const Eigen::MatrixXd& noise_cov) const {
  bool valid = kernel_valid_;
  for (int i = 0; i < dim_ && valid; ++i) {
    valid = kernel_spacing_[i] == spacing_[i];
    for (int j = 0; j < dim_; ++j) valid = valid && kernel_cov_[3 * i + j] == noise_cov(i, j);
  }
  return valid;
}

void GridObserver::ConvolveTaps() {
  // Direct: out(j) = Σ_taps w · in(j − offset), zero outside the grid; per output line along axis 0, every tap.
  const int lines = total_ / n_[0];
  for (int line = 0; line < lines; ++line) ConvolveTapsLine(line);
  for (int idx = 0; idx < total_; ++idx) q_[idx] = std::max(0.0, r_[idx]);
}

void GridObserver::ConvolveTapsLine(int line) {
  const int n0 = n_[0];
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
    const bool three = t + 2 < taps_ && tap_offset_[t + 1][0] == off[0] + 1 && tap_offset_[t + 2][0] == off[0] + 2 &&
                       tap_offset_[t + 1][1] == off[1] && tap_offset_[t + 2][1] == off[1] &&
                       tap_offset_[t + 1][2] == off[2] && tap_offset_[t + 2][2] == off[2];
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

void GridObserver::ConvolveFft(const Eigen::MatrixXd& noise_cov, const LogDensity* log_noise) {
  std::fill(buf_.begin(), buf_.end(), 0.0);
  for (int idx = 0; idx < total_; ++idx) buf_[PaddedIndex(idx)] = q_[idx];
  FftLines(buf_, false, true);
  if (log_noise == nullptr) {
    if (!spectrum_valid_) BuildSpectrum(noise_cov);
    for (int flat = 0; flat < padded_total_; ++flat) buf_[flat] *= spectrum_[flat];
  } else {
    SampledNoiseSpectrum(*log_noise);
    for (int flat = 0; flat < padded_total_; ++flat) buf_[flat] *= kernel_[flat];
  }
  FftLines(buf_, true, true);
  for (int idx = 0; idx < total_; ++idx) q_[idx] = std::max(0.0, buf_[PaddedIndex(idx)].real());
}

void GridObserver::SampledNoiseSpectrum(const LogDensity& log_noise) {
  // Any density: sample f_N at the grid offsets (wrapped), normalise, transform.
  double max_log = -std::numeric_limits<double>::infinity();
  for (int flat = 0; flat < padded_total_; ++flat) {
    for (int i = 0; i < dim_; ++i) x_(i) = SignedPaddedIndex(flat, i) * spacing_[i];
    const double l = log_noise(x_);
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
}

}  // namespace ident
