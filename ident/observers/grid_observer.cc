#include "ident/observers/grid_observer.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>
#include <Eigen/LU>

#include "common/dense_decompositions.h"
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

// Spacing kept while the needed box fills at least this fraction of the grid; a new grid is the box
// widened by kGridSlack.
constexpr double kGridFill = 0.6;
constexpr double kGridSlack = 1.2;

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
  const Eigen::LLT<Eigen::MatrixXd> llt = dense::Llt(P0);
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
  const Eigen::MatrixXd Pinv = dense::Inverse(llt);
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
  double cell = 1;
  for (int i = 0; i < dim_; ++i) cell *= spacing_[i];
  double max_q = 0;
  bool ok = std::isfinite(cell) && cell >= std::numeric_limits<double>::min();
  if (ok) {
    for (double v : q_) max_q = std::max(max_q, v);
    ok = std::isfinite(max_q) && max_q > 0;
  }
  // q ← q · 2^−e with max q ∈ [1/2, 1) first, exact in binary: a likelihood can leave q subnormal, where
  // each product in the moments keeps only a few significant bits (the mean could leave the grid).
  double sum = 0;
  if (ok) {
    int e = 0;
    std::frexp(max_q, &e);
    if (e > -1022) {  // 2^−e is a double: one exact multiplication per node
      const double factor = std::ldexp(1.0, -e);
      for (double& v : q_) v *= factor;
    } else {
      for (double& v : q_) v = std::ldexp(v, -e);
    }
    ok = Moments(q_, sum, mean_new_, cov_new_);
  }
  double scale = 0;
  if (ok) {
    scale = 1.0 / (sum * cell);
    ok = scale > 0 && std::isfinite(scale);
  }
  if (ok) {
    max_q = 0;
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
