#include "studies/mems/excursion_reading.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Eigenvalues>

#include "common/dense_decompositions.h"
#include "common/error.h"
#include "models/truncated_bivariate_normal.h"
#include "studies/mems/crossing_reading.h"
#include "studies/mems/ep_site_change.h"

namespace ident {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Inverse of the leading dim × dim block of a symmetric 2 × 2 matrix (dim 1: only (0, 0) is used).
Eigen::Matrix2d InverseBlock(const Eigen::Matrix2d& a, int dim) {
  Eigen::Matrix2d inv = Eigen::Matrix2d::Zero();
  if (dim == 1) {
    inv(0, 0) = 1 / a(0, 0);
    return inv;
  }
  const double det = a(0, 0) * a(1, 1) - a(0, 1) * a(1, 0);
  inv << a(1, 1), -a(0, 1), -a(1, 0), a(0, 0);
  return inv / det;
}

}  // namespace

ExcursionReading::ExcursionReading(const models::ThresholdSensor& sensor, int num_states, ExcursionOptions options)
    : c_(sensor.c()), threshold_(sensor.threshold()), options_(options), n_(num_states) {
  IDENT_REQUIRE(num_states >= 1 && num_states == sensor.num_states(),
                "num_states = {}; need >= 1 and equal to the sensor's {}", num_states, sensor.num_states());
  IDENT_REQUIRE(options.max_length >= 2, "max_length = {}; need >= 2", options.max_length);
  IDENT_REQUIRE(options.max_sweeps >= 1, "max_sweeps = {}; need >= 1", options.max_sweeps);
  IDENT_REQUIRE(options.tolerance > 0, "tolerance = {}; need > 0", options.tolerance);
  const int d = n_ + options.max_length;
  mu_ = Eigen::VectorXd::Zero(d);
  work_v_ = Eigen::VectorXd::Zero(d);
  sigma_ = Eigen::MatrixXd::Zero(d, d);
  gain_ = Eigen::MatrixXd::Zero(d, 2);
  work_m_ = Eigen::MatrixXd::Zero(d, 2);
  factors_.reserve(options.max_length);
}

void ExcursionReading::Propagate(const models::LinearStateSpace& model, const Eigen::Ref<const Eigen::VectorXd>& u) {
  const int n = n_, l = length_;
  work_v_.head(n).noalias() = model.A * mu_.head(n);  // μ_x ← A μ_x + B u
  if (model.num_inputs() > 0) work_v_.head(n).noalias() += model.B * u;
  mu_.head(n) = work_v_.head(n);
  // Σ_xs ← A Σ_xs, Σ_xx ← A Σ_xx A' + P_N (factors depend on s only, so this is the posterior's time update).
  if (l > 0) {
    const Eigen::MatrixXd xs = model.A * sigma_.block(0, n, n, l);
    sigma_.block(0, n, n, l) = xs;
    sigma_.block(n, 0, l, n) = xs.transpose();
  }
  const Eigen::MatrixXd xx = model.A * sigma_.topLeftCorner(n, n) * model.A.transpose() + model.process_noise;
  sigma_.topLeftCorner(n, n) = 0.5 * (xx + xx.transpose());
}

void ExcursionReading::AppendReadingCoordinate() {
  const int n = n_, d = n_ + length_, j = d;
  mu_(j) = c_.dot(mu_.head(n));  // s_k = c'x(k)
  work_v_.head(d).noalias() = sigma_.topRows(n).leftCols(d).transpose() * c_;
  sigma_.row(j).head(d) = work_v_.head(d).transpose();
  sigma_.col(j).head(d) = work_v_.head(d);
  sigma_(j, j) = c_.dot(work_v_.head(n));
  ++length_;
}

void ExcursionReading::SetMarginal(const Factor& f, const Eigen::Vector2d& mean, const Eigen::Matrix2d& cov) {
  const int d = n_ + length_, a = n_ + f.first, k = f.dim;
  const Eigen::Matrix2d sigma_aa =
      k == 2 ? Eigen::Matrix2d(sigma_.block(a, a, 2, 2)) : Eigen::Matrix2d{{sigma_(a, a), 0}, {0, 0}};
  const Eigen::Matrix2d inv = InverseBlock(sigma_aa, k);
  // K = Σ_{·A} Σ_AA⁻¹ (d × k); μ ← μ + K(μ_A' − μ_A); Σ ← Σ + K(Σ_AA' − Σ_AA)K'.
  gain_.leftCols(k).topRows(d).noalias() = sigma_.block(0, a, d, k) * inv.topLeftCorner(k, k);
  const Eigen::Vector2d dm = mean - (k == 2 ? Eigen::Vector2d(mu_.segment(a, 2)) : Eigen::Vector2d(mu_(a), 0));
  const Eigen::Matrix2d dc = cov - sigma_aa;
  if (dm.head(k).isZero(0.0) && dc.topLeftCorner(k, k).isZero(0.0)) return;  // an inactive factor: nothing moves
  mu_.head(d).noalias() += gain_.leftCols(k).topRows(d) * dm.head(k);
  work_m_.leftCols(k).topRows(d).noalias() = gain_.leftCols(k).topRows(d) * dc.topLeftCorner(k, k);
  sigma_.topLeftCorner(d, d).noalias() += work_m_.leftCols(k).topRows(d) * gain_.leftCols(k).topRows(d).transpose();
}

void ExcursionReading::Cavity(const Factor& f, Eigen::Vector2d& mean, Eigen::Matrix2d& cov) const {
  const int a = n_ + f.first, k = f.dim;
  const Eigen::Matrix2d sigma_aa =
      k == 2 ? Eigen::Matrix2d(sigma_.block(a, a, 2, 2)) : Eigen::Matrix2d{{sigma_(a, a), 0}, {0, 0}};
  const Eigen::Vector2d mu_a = k == 2 ? Eigen::Vector2d(mu_.segment(a, 2)) : Eigen::Vector2d(mu_(a), 0);
  const Eigen::Matrix2d prec = InverseBlock(sigma_aa, k);
  Eigen::Matrix2d cav_prec = prec - f.lambda;  // cavity = posterior / site
  if (k == 1) cav_prec(0, 1) = cav_prec(1, 0) = cav_prec(1, 1) = 0;
  const Eigen::Vector2d cav_h = prec * mu_a - f.eta;
  cov = InverseBlock(cav_prec, k);
  mean = cov * cav_h;
  if (k == 1) mean(1) = 0;
}

void ExcursionReading::Remove(const Factor& f) {
  Eigen::Vector2d m;
  Eigen::Matrix2d v;
  Cavity(f, m, v);
  SetMarginal(f, m, v);
}

double ExcursionReading::Refit(Factor& f) {
  Eigen::Vector2d mc;
  Eigen::Matrix2d vc;
  Cavity(f, mc, vc);
  // An unchanged cavity (within the tolerance, relative to its sd / variance) gives the same site: skip
  // the refit and its O(d²) joint update (the fixed point is the same).
  if (std::isfinite(f.last_mean(0))) {
    double moved = 0;
    for (int i = 0; i < f.dim; ++i) {
      moved = std::max(moved, std::abs(mc(i) - f.cavity_mean(i)) / std::sqrt(vc(i, i)));
      for (int j = 0; j < f.dim; ++j)
        moved = std::max(moved, std::abs(vc(i, j) - f.cavity_cov(i, j)) / std::sqrt(vc(i, i) * vc(j, j)));
    }
    if (moved <= options_.tolerance) return 0.0;
  }
  f.cavity_mean = mc;
  f.cavity_cov = vc;
  Eigen::Vector2d mt = Eigen::Vector2d::Zero();
  Eigen::Matrix2d vt = Eigen::Matrix2d::Zero();
  if (f.dim == 2) {
    const auto t = models::TruncatedBivariateNormalMoments(mc, vc, f.bounds, f.sides);  // Tallis
    if (!t.ok) return -1;
    mt = t.mean;
    vt = t.covariance;
  } else {
    if (!(vc(0, 0) > 0)) return -1;
    const double lo = f.sides(0) > 0 ? f.bounds(0) : -kInf, hi = f.sides(0) > 0 ? kInf : f.bounds(0);
    const auto t = models::TruncatedNormalMoments(mc(0), vc(0, 0), lo, hi);
    if (!t.ok) return -1;
    mt(0) = t.mean;
    vt(0, 0) = t.variance;
  }
  // New site = tilted / cavity: λ = V_t⁻¹ − V_c⁻¹ (≥ 0 for a log-concave factor; round-off clipped),
  // η = V_t⁻¹ μ_t − V_c⁻¹ μ_c; the posterior's marginal becomes cavity × site.
  const Eigen::Matrix2d pc = InverseBlock(vc, f.dim), pt = InverseBlock(vt, f.dim);
  Eigen::Matrix2d lambda = pt - pc;
  if (f.dim == 2) {
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig =
        dense::SymmetricEigen2x2(0.5 * (lambda + lambda.transpose()));
    lambda = eig.eigenvectors() * eig.eigenvalues().cwiseMax(0.0).asDiagonal() * eig.eigenvectors().transpose();
  } else {
    lambda(0, 0) = std::max(lambda(0, 0), 0.0);
  }
  f.lambda = lambda;
  f.eta = pt * mt - pc * mc;
  const Eigen::Matrix2d target_cov = InverseBlock(pc + lambda, f.dim);
  const Eigen::Vector2d target_mean = target_cov * (pc * mc + f.eta);
  SetMarginal(f, target_mean, target_cov);
  // Convergence: change of the tilted moments since the last refit, relative to their scale.
  return internal::RecordTiltedChange(mt, vt, f.dim, f.last_mean, f.last_cov);
}

StepReport ExcursionReading::Sweep(LcGaussianFilter& filter) {
  last_converged_ = false;
  for (last_sweeps_ = 1; last_sweeps_ <= options_.max_sweeps; ++last_sweeps_) {
    double change = 0;
    for (Factor& f : factors_) {
      const double c = Refit(f);
      if (!(c >= 0)) {
        length_ = 0;
        factors_.clear();
        return {StepStatus::kNumericalFailure};
      }
      change = std::max(change, c);
    }
    if (change <= options_.tolerance) {
      last_converged_ = true;
      break;
    }
  }
  last_sweeps_ = std::min(last_sweeps_, options_.max_sweeps);
  const StepReport r = filter.Assign(mu_.head(n_), sigma_.topLeftCorner(n_, n_));
  if (!r.updated()) {
    length_ = 0;
    factors_.clear();
  }
  return r;
}

StepReport ExcursionReading::Step(LcGaussianFilter& filter, const Eigen::Ref<const Eigen::VectorXd>& mean_before,
                                  const Eigen::Ref<const Eigen::MatrixXd>& cov_before,
                                  const models::LinearStateSpace& model, const Eigen::Ref<const Eigen::VectorXd>& u,
                                  double y_prev, double y) {
  auto valid = [](double r) { return r == -1.0 || r == 0.0 || r == 1.0; };
  if (!valid(y_prev) || !valid(y) || filter.num_states() != n_ || mean_before.size() != n_ || cov_before.rows() != n_ ||
      cov_before.cols() != n_ || model.A.rows() != n_ || model.A.cols() != n_ || model.process_noise.rows() != n_ ||
      u.size() != model.num_inputs()) {
    return {StepStatus::kRejectedInvalid};
  }
  auto new_factor = [](int first, int dim) {
    Factor f;
    f.first = first;
    f.dim = dim;
    f.lambda.setZero();
    f.eta.setZero();
    f.last_mean.setConstant(std::numeric_limits<double>::quiet_NaN());
    f.last_cov.setConstant(std::numeric_limits<double>::quiet_NaN());
    f.bounds.setZero();
    f.sides.setOnes();
    return f;
  };
  if (!active()) {
    if (!(y_prev == 0 && y != 0)) return {StepStatus::kRejectedInvalid};
    // Open: joint of x(k−1) ~ N(mean_before, cov_before), s_{k−1}, then x(k) and s_k.
    mu_.head(n_) = mean_before;
    sigma_.topLeftCorner(n_, n_) = cov_before;
    length_ = 0;
    factors_.clear();
    AppendReadingCoordinate();
    Propagate(model, u);
    AppendReadingCoordinate();
    Factor entry = new_factor(0, 2);
    const ReadingChangeRegion region = ThresholdChangeRegion(threshold_, y_prev, y);  // x1(k−1) < T ≤ x1(k)
    entry.bounds = region.bounds;
    entry.sides = region.sides;
    factors_.push_back(entry);
    side_ = y;
    return Sweep(filter);
  }
  if (y_prev != side_ || (y != side_ && y != 0) || length_ + 1 > options_.max_length) {
    length_ = 0;  // close the excursion; the filter keeps its state
    factors_.clear();
    return {StepStatus::kRejectedInvalid};
  }
  Propagate(model, u);
  AppendReadingCoordinate();
  const int last = length_ - 1;  // index of s_k
  if (y == side_) {              // repeated reading: y s_k ≥ T
    Factor f = new_factor(last, 1);
    f.sides(0) = side_;
    f.bounds(0) = side_ * threshold_;
    factors_.push_back(f);
    return Sweep(filter);
  }
  // Exit ±1 → 0: the wedge of (s_{k−1}, s_k) replaces the repeated reading's factor on s_{k−1}; after a
  // one-sample excursion s_{k−1} belongs to the entry wedge, and the exit is the half-line s_k·side < T.
  const ReadingChangeRegion region = ThresholdChangeRegion(threshold_, y_prev, y);
  if (factors_.back().dim == 1 && factors_.back().first == last - 1) {
    Remove(factors_.back());
    factors_.pop_back();
    Factor f = new_factor(last - 1, 2);
    f.bounds = region.bounds;
    f.sides = region.sides;
    factors_.push_back(f);
  } else {
    Factor f = new_factor(last, 1);
    f.bounds(0) = region.bounds(1);
    f.sides(0) = region.sides(1);
    factors_.push_back(f);
  }
  const StepReport r = Sweep(filter);
  length_ = 0;
  factors_.clear();
  return r;
}

}  // namespace ident
