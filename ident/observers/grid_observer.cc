#include "ident/observers/grid_observer.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include <fmt/format.h>
#include <Eigen/Cholesky>
#include <Eigen/LU>

#include "common/error.h"

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
  p_.assign(total_, 0.0);
  q_.assign(total_, 0.0);
  p_saved_.assign(total_, 0.0);
  buf_.assign(padded_total_, 0.0);
  kernel_.assign(padded_total_, 0.0);
  const int max_np = *std::max_element(np_.begin(), np_.end());
  line_in_.assign(max_np, 0.0);
  line_out_.assign(max_np, 0.0);
  mean_.resize(dim_);
  x_.resize(dim_);
  cov_.resize(dim_, dim_);
  mean_saved_.resize(dim_);
  cov_saved_.resize(dim_, dim_);
  const Eigen::MatrixXd Pinv = llt.solve(Eigen::MatrixXd::Identity(dim_, dim_));
  for (int idx = 0; idx < total_; ++idx) {
    NodeCoordinates(idx, x_);
    const Eigen::VectorXd d = x_ - m0;
    p_[idx] = std::exp(-0.5 * d.dot(Pinv * d));
  }
  IDENT_REQUIRE(Normalise() && UpdateMoments(),
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
  Save();
  std::array<double, 3> mid{}, half{};
  SupportBox(mid, half);
  const auto old_origin = origin_;
  const auto old_spacing = spacing_;
  if (!MoveGrid(model, shift, mid, half)) {
    Restore();
    return {StepStatus::kNumericalFailure};
  }
  PushForward(Ainv, shift, old_origin, old_spacing);
  // (2): convolution with f_N.
  Convolve(model.process_noise, log_noise);
  return Commit();
}

void GridObserver::SupportBox(std::array<double, 3>& mid, std::array<double, 3>& half) const {
  // Nodes above support_level · max. No extra margin: a margin would compound from step to step and the
  // grid would keep coarsening.
  const double level = options_.support_level * *std::max_element(p_.begin(), p_.end());
  std::array<int, 3> lo{n_[0], n_[1], n_[2]}, hi{-1, -1, -1};
  for (int idx = 0; idx < total_; ++idx) {
    if (p_[idx] <= level) continue;
    int r = idx;
    for (int i = 0; i < dim_; ++i) {
      const int j = r % n_[i];
      r /= n_[i];
      lo[i] = std::min(lo[i], j);
      hi[i] = std::max(hi[i], j);
    }
  }
  for (int i = 0; i < dim_; ++i) {
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
    const double hw =
        std::max(options_.min_half_width,
                 new_half(i) + options_.noise_sigmas * std::sqrt(std::max(0.0, model.process_noise(i, i))));
    origin_[i] = new_mid(i) - hw;
    spacing_[i] = 2 * hw / (n_[i] - 1);
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
  // (1): f^d(x) = f_{k−1}(A⁻¹(x − B u)), multilinear interpolation in fractional old indices
  //      f = f0 + Σ_i j_i G(:, i).
  SmallVector new_origin(dim_);
  for (int i = 0; i < dim_; ++i) new_origin(i) = origin_[i] - shift(i);
  SmallVector f0(dim_);
  f0.noalias() = Ainv * new_origin;
  SmallMatrix G = Ainv;
  for (int j = 0; j < dim_; ++j) {
    f0(j) = (f0(j) - old_origin[j]) / old_spacing[j];
    for (int i = 0; i < dim_; ++i) G(j, i) *= spacing_[i] / old_spacing[j];
  }
  for (int idx = 0; idx < total_; ++idx) {
    std::array<double, 3> f{}, w{};
    std::array<int, 3> base{};
    int r = idx;
    bool inside = true;
    for (int j = 0; j < dim_; ++j) f[j] = f0(j);
    for (int i = 0; i < dim_; ++i) {
      const int ji = r % n_[i];
      r /= n_[i];
      for (int j = 0; j < dim_; ++j) f[j] += ji * G(j, i);
    }
    for (int j = 0; j < dim_ && inside; ++j) {
      if (!(f[j] >= 0 && f[j] <= n_[j] - 1)) {
        inside = false;
        break;
      }  // also NaN (no int cast of NaN)
      base[j] = std::min(static_cast<int>(f[j]), n_[j] - 2);
      w[j] = f[j] - base[j];
    }
    if (!inside) {
      q_[idx] = 0;
      continue;
    }
    double v = 0;
    for (int corner = 0; corner < (1 << dim_); ++corner) {
      double weight = 1;
      int flat = 0, stride = 1;
      for (int j = 0; j < dim_; ++j) {
        const int bit = (corner >> j) & 1;
        weight *= bit ? w[j] : 1 - w[j];
        flat += (base[j] + bit) * stride;
        stride *= n_[j];
      }
      v += weight * p_[flat];
    }
    q_[idx] = v;
  }
  p_.swap(q_);
}

void GridObserver::Convolve(const Eigen::MatrixXd& noise_cov, const LogDensity* log_noise) {
  // Lines along one axis of a padded array: FFT each.
  auto transform = [&](std::vector<std::complex<double>>& data, bool inverse) {
    for (int axis = 0; axis < dim_; ++axis) {
      const int len = np_[axis];
      int stride = 1;
      for (int i = 0; i < axis; ++i) stride *= np_[i];
      const int lines = padded_total_ / len;
      for (int line = 0; line < lines; ++line) {
        const int start = (line % stride) + (line / stride) * stride * len;
        for (int k = 0; k < len; ++k) line_in_[k] = data[start + k * stride];
        if (inverse)
          fft_.inv(line_out_.data(), line_in_.data(), len);
        else
          fft_.fwd(line_out_.data(), line_in_.data(), len);
        for (int k = 0; k < len; ++k) data[start + k * stride] = line_out_[k];
      }
    }
  };
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
  for (int idx = 0; idx < total_; ++idx) buf_[padded_index(idx)] = p_[idx];
  transform(buf_, false);
  // Signed frequency / offset index of padded node `flat` along each axis.
  auto signed_index = [&](int flat, int i) {
    int r = flat;
    for (int a = 0; a < i; ++a) r /= np_[a];
    const int k = r % np_[i];
    return k < (np_[i] + 1) / 2 ? k : k - np_[i];
  };
  if (log_noise == nullptr) {
    // Gaussian: multiply by a lattice version of the characteristic function exp(−½ ω'P_N ω). The
    // continuous one jumps at the Nyquist frequency when P_N is narrow against the grid, and that jump
    // becomes a slowly decaying 1/x tail in space. With s_i = (2/Δ_i) sin(ω_i Δ_i/2) (periodic) and
    // d_i = cos(ω_i Δ_i/2) we use the exponent −½[(D s)'P_N(D s) + Σ_i P_N,ii (1 − d_i²) s_i²]: smooth
    // and periodic in ω, ≥ 0 since P_N ≥ 0, equal to −½ω'P_N ω to second order, so the kernel has
    // exactly the covariance P_N (for diagonal P_N it is the lattice heat kernel).
    Eigen::Vector3d s = Eigen::Vector3d::Zero(), ds = Eigen::Vector3d::Zero();
    for (int flat = 0; flat < padded_total_; ++flat) {
      double quad = 0;
      for (int i = 0; i < dim_; ++i) {
        const double half_angle = std::numbers::pi * signed_index(flat, i) / np_[i];
        s(i) = 2 * std::sin(half_angle) / spacing_[i];
        const double d = std::cos(half_angle);
        ds(i) = d * s(i);
        quad += noise_cov(i, i) * (1 - d * d) * s(i) * s(i);
      }
      for (int i = 0; i < dim_; ++i)
        for (int j = 0; j < dim_; ++j) quad += ds(i) * noise_cov(i, j) * ds(j);
      buf_[flat] *= std::exp(-0.5 * quad);
    }
  } else {
    // Any density: sample f_N at the grid offsets (wrapped), normalise, transform, multiply.
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
    transform(kernel_, false);
    for (int flat = 0; flat < padded_total_; ++flat) buf_[flat] *= kernel_[flat];
  }
  transform(buf_, true);
  for (int idx = 0; idx < total_; ++idx) p_[idx] = std::max(0.0, buf_[padded_index(idx)].real());
}

bool GridObserver::Normalise() {
  double sum = 0;
  for (double v : p_) sum += v;
  double cell = 1;
  for (int i = 0; i < dim_; ++i) cell *= spacing_[i];
  // A cell volume outside the normal doubles, or a sum that is 0, NaN or infinite: not normalisable.
  if (!(cell >= std::numeric_limits<double>::min()) || !std::isfinite(cell)) return false;
  if (!(sum > 0) || !std::isfinite(sum)) return false;
  const double scale = 1.0 / (sum * cell);
  if (!(scale > 0) || !std::isfinite(scale)) return false;
  bool finite = true;
  for (double& v : p_) {
    v *= scale;
    finite = finite && std::isfinite(v);
  }
  return finite;
}

void GridObserver::Save() {
  std::copy(p_.begin(), p_.end(), p_saved_.begin());
  origin_saved_ = origin_;
  spacing_saved_ = spacing_;
  mean_saved_ = mean_;
  cov_saved_ = cov_;
}

void GridObserver::Restore() {
  std::copy(p_saved_.begin(), p_saved_.end(), p_.begin());
  origin_ = origin_saved_;
  spacing_ = spacing_saved_;
  mean_ = mean_saved_;
  cov_ = cov_saved_;
}

StepReport GridObserver::Commit() {
  if (Normalise() && UpdateMoments()) return {StepStatus::kUpdated};
  Restore();
  return {StepStatus::kNumericalFailure};
}

bool GridObserver::UpdateMoments() {
  double cell = 1;
  for (int i = 0; i < dim_; ++i) cell *= spacing_[i];
  mean_.setZero();
  for (int idx = 0; idx < total_; ++idx) {
    if (p_[idx] == 0) continue;
    NodeCoordinates(idx, x_);
    mean_ += p_[idx] * x_;
  }
  mean_ *= cell;
  cov_.setZero();
  for (int idx = 0; idx < total_; ++idx) {
    if (p_[idx] == 0) continue;
    NodeCoordinates(idx, x_);
    x_ -= mean_;
    cov_.noalias() += p_[idx] * x_ * x_.transpose();
  }
  cov_ *= cell;
  return mean_.allFinite() && cov_.allFinite();
}

StepReport GridObserver::Correct(const models::MeasurementFunction& measurement, double y) {
  if (measurement.num_states() != dim_ || !measurement.IsValidOutput(y)) return {StepStatus::kRejectedInvalid};
  // (3) in log space: q = log f_M(y, x) on nodes with mass, shifted by its maximum before exp.
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
  Save();
  for (int idx = 0; idx < total_; ++idx) p_[idx] *= std::exp(q_[idx] - max_log);
  return Commit();
}

StepReport GridObserver::Update(const StateSpaceItem& item) {
  IDENT_REQUIRE(measurement_ != nullptr, "GridObserver::Update needs the constructor that takes a model");
  const StepReport predicted = Predict(model_, item.u);
  if (!predicted.updated()) return predicted;
  return Correct(*measurement_, item.y);
}

}  // namespace ident
