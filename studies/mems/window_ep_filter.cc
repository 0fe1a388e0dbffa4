#include "studies/mems/window_ep_filter.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Eigenvalues>
#include <Eigen/LU>

#include "common/dense_decompositions.h"
#include "common/error.h"
#include "models/truncated_bivariate_normal.h"
#include "studies/mems/crossing_reading.h"
#include "studies/mems/ep_site_change.h"

namespace ident {
namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
// A 1-D site whose cavity has every bound farther than this many sd is the identity to double precision
// (normal tail mass beyond 8.5 sd is 9.5e-18).
constexpr double kFarSd = 8.5;

using Mat23 = Eigen::Matrix<double, 2, 3>;

void Symmetrize(Eigen::Matrix3d& m) { m = 0.5 * (m + m.transpose()).eval(); }

}  // namespace

WindowEpFilter::WindowEpFilter(const models::ThresholdSensor& sensor, const Eigen::Vector2d& mean,
                               const Eigen::Matrix2d& covariance, WindowEpOptions options)
    : threshold_(sensor.threshold()), options_(options) {
  IDENT_REQUIRE(sensor.num_states() == 2, "WindowEpFilter: the sensor reads {} states; need 2", sensor.num_states());
  IDENT_REQUIRE(options.window >= 1, "WindowEpFilter: window = {}; need >= 1", options.window);
  IDENT_REQUIRE(options.max_sweeps >= 1, "WindowEpFilter: max_sweeps = {}; need >= 1", options.max_sweeps);
  IDENT_REQUIRE(options.tolerance > 0, "WindowEpFilter: tolerance = {}; need > 0", options.tolerance);
  IDENT_REQUIRE(mean.allFinite() && covariance.allFinite(), "WindowEpFilter: prior mean/covariance not finite");
  IDENT_REQUIRE(
      (covariance - covariance.transpose()).cwiseAbs().maxCoeff() <= 1e-12 * (1 + covariance.cwiseAbs().maxCoeff()),
      "WindowEpFilter: prior covariance not symmetric");
  IDENT_REQUIRE(dense::SymmetricEigen2x2(covariance).eigenvalues().minCoeff() >= 0,
                "WindowEpFilter: prior covariance not positive semidefinite");
  h_ << sensor.c()(0), sensor.c()(1), 0.0;
  // z(0) = (x(0), s(−1)); s(−1) is never read (no wedge at the first step), so it is set to c'x(0).
  base_m_ << mean, h_.head<2>().dot(mean);
  base_P_.setZero();
  base_P_.topLeftCorner<2, 2>() = covariance;
  const Eigen::Vector2d pc = covariance * h_.head<2>();
  base_P_.block<2, 1>(0, 2) = pc;
  base_P_.block<1, 2>(2, 0) = pc.transpose();
  base_P_(2, 2) = h_.head<2>().dot(pc);
  capacity_ = options.window + 1;
  ring_.resize(static_cast<size_t>(capacity_));
}

double WindowEpFilter::Refit(Slot& s) {
  if (s.dim == 0) return 0.0;
  // Cavity α⁻ · β (moment form): P_c = (I + P⁻Ω)⁻¹ P⁻, m_c = m⁻ + P_c (ω − Ω m⁻).
  // β_j never involves s(j−1) (Ω, ω have a zero third row: F's third column is zero, see Backward), so a
  // 1-D site on s(j) = c'x(j) needs only the cavity of x(j): (I + P⁻_xx Ω_xx)⁻¹ P⁻_xx, 2 × 2.
  const bool no_beta = s.Omega.isZero(0.0) && s.omega.isZero(0.0);
  ++refits_;
  Eigen::Vector2d mt, mu;
  Eigen::Matrix2d vt, vc;
  bool zero_site = false;
  if (s.dim == 1) {
    const Eigen::Vector2d c = h_.head<2>();
    double m, v;
    if (no_beta) {
      m = c.dot(s.pred_m.head<2>());
      v = c.dot(s.pred_P.topLeftCorner<2, 2>() * c);
    } else {
      const Eigen::Matrix2d Pp = s.pred_P.topLeftCorner<2, 2>(), Om = s.Omega.topLeftCorner<2, 2>();
      const Eigen::Vector2d mp = s.pred_m.head<2>();
      const Eigen::Matrix2d Pcx = (Eigen::Matrix2d::Identity() + Pp * Om).inverse() * Pp;
      m = c.dot(mp + Pcx * (s.omega.head<2>() - Om * mp));
      v = 0.5 * (c.dot(Pcx * c) + c.dot(Pcx.transpose() * c));
    }
    if (!(v > 0) || !std::isfinite(m)) return -1;
    // An unchanged cavity (within the tolerance, relative to its sd / variance) gives the same site.
    if (std::isfinite(s.last_mean(0)) && std::abs(m - s.cav_mean(0)) <= options_.tolerance * std::sqrt(v) &&
        std::abs(v - s.cav_cov(0, 0)) <= options_.tolerance * v) {
      return 0.0;
    }
    s.cav_mean << m, 0;
    s.cav_cov << v, 0, 0, 0;
    const double sd = std::sqrt(v);
    if ((s.lo == -kInfinity || m - s.lo > kFarSd * sd) && (s.hi == kInfinity || s.hi - m > kFarSd * sd)) {
      zero_site = true;
      mt << m, 0;
      vt << v, 0, 0, 0;
    } else {
      const auto t = models::TruncatedNormalMoments(m, v, s.lo, s.hi);
      if (!t.ok) return -1;
      const double lam = std::max(1 / t.variance - 1 / v, 0.0);
      const double vq = 1 / (1 / v + lam);  // posterior variance on s(j) after the refit
      s.lambda << lam, 0, 0, 0;
      s.eta << t.mean / vq - m / v, 0;
      mt << t.mean, 0;
      vt << t.variance, 0, 0, 0;
    }
    mu << m, 0;
  } else {
    Mat3 Pc = s.pred_P;
    Vec3 mc = s.pred_m;
    if (!no_beta) {
      Pc = (Mat3::Identity() + s.pred_P * s.Omega).inverse() * s.pred_P;
      Symmetrize(Pc);
      mc = s.pred_m + Pc * (s.omega - s.Omega * s.pred_m);
    }
    Mat23 H;
    H.row(0) << 0, 0, 1;        // s(j−1)
    H.row(1) = h_.transpose();  // s(j)
    mu = H * mc;
    vc = H * Pc * H.transpose();
    vc = 0.5 * (vc + vc.transpose()).eval();
    if (std::isfinite(s.last_mean(0))) {
      double moved = 0;
      for (int i = 0; i < 2; ++i) {
        moved = std::max(moved, std::abs(mu(i) - s.cav_mean(i)) / std::sqrt(vc(i, i)));
        for (int k = 0; k < 2; ++k)
          moved = std::max(moved, std::abs(vc(i, k) - s.cav_cov(i, k)) / std::sqrt(vc(i, i) * vc(k, k)));
      }
      if (moved <= options_.tolerance) return 0.0;
    }
    s.cav_mean = mu;
    s.cav_cov = vc;
    const auto t = models::TruncatedBivariateNormalMoments(mu, vc, s.bounds, s.sides);  // Tallis
    if (!t.ok) return -1;
    const Eigen::Matrix2d pc = vc.inverse(), pt = t.covariance.inverse();
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig;
    eig.computeDirect(0.5 * (pt - pc + (pt - pc).transpose()));
    const Eigen::Matrix2d lam =
        eig.eigenvectors() * eig.eigenvalues().cwiseMax(0.0).asDiagonal() * eig.eigenvectors().transpose();
    s.lambda = lam;
    s.eta = (pc + lam) * t.mean - pc * mu;  // posterior mean on (s(j−1), s(j)) = μ_t
    mt = t.mean;
    vt = t.covariance;
  }
  if (zero_site) {
    const bool already_zero = s.lambda.isZero(0.0) && s.eta.isZero(0.0);
    s.lambda.setZero();
    s.eta.setZero();
    if (already_zero && std::isfinite(s.last_mean(0))) {
      s.last_mean = mt;
      s.last_cov = vt;
      return 0.0;
    }
  }
  // Convergence: change of the tilted moments since the last refit, relative to their scale.
  return internal::RecordTiltedChange(mt, vt, s.dim, s.last_mean, s.last_cov);
}

void WindowEpFilter::Filtered(Slot& s) {
  if (s.dim == 0 || (s.lambda.isZero(0.0) && s.eta.isZero(0.0))) {
    s.filt_m = s.pred_m;
    s.filt_P = s.pred_P;
    return;
  }
  Mat3 Lz;
  Vec3 ez;
  if (s.dim == 1) {
    // Rank one (a pseudo-reading of s(j) with precision λ, information η):
    // P = P⁻ − g g' λ/(1 + λ h'P⁻h), g = P⁻h;  m = m⁻ + P h (η − λ h'm⁻).
    const Vec3 g = s.pred_P * h_;
    const double lam = s.lambda(0, 0), d = 1 + lam * h_.dot(g);
    s.filt_P = s.pred_P - (lam / d) * g * g.transpose();
    Symmetrize(s.filt_P);
    s.filt_m = s.pred_m + (g / d) * (s.eta(0) - lam * h_.dot(s.pred_m));
    return;
  } else {
    Mat23 H;
    H.row(0) << 0, 0, 1;
    H.row(1) = h_.transpose();
    Lz = H.transpose() * s.lambda * H;
    ez = H.transpose() * s.eta;
  }
  s.filt_P = (Mat3::Identity() + s.pred_P * Lz).inverse() * s.pred_P;
  Symmetrize(s.filt_P);
  s.filt_m = s.pred_m + s.filt_P * (ez - Lz * s.pred_m);
}

void WindowEpFilter::Forward(Slot& s, const Vec3& m_prev, const Mat3& P_prev) {
  // z(j) = F z(j−1) + b + w with F = [A 0; c' 0]: only the x block of z(j−1) enters.
  const Eigen::Matrix2d A = s.F.topLeftCorner<2, 2>(), Pxx = P_prev.topLeftCorner<2, 2>();
  const Eigen::Vector2d c = h_.head<2>(), mx = m_prev.head<2>();
  const Eigen::Matrix2d AP = A * Pxx;
  const Eigen::Vector2d Pc = Pxx * c;
  s.pred_m << A * mx + s.b.head<2>(), c.dot(mx);
  const Eigen::Matrix2d Pn = AP * A.transpose() + s.Q.topLeftCorner<2, 2>();
  s.pred_P.topLeftCorner<2, 2>() = 0.5 * (Pn + Pn.transpose());
  s.pred_P.block<2, 1>(0, 2) = A * Pc;
  s.pred_P.block<1, 2>(2, 0) = (A * Pc).transpose();
  s.pred_P(2, 2) = c.dot(Pc);
}

void WindowEpFilter::Backward(const Slot& s, Slot& prev) {
  if (s.dim != 2) {
    // Ω_j + site j has a zero third row here (a 1-D site reads s(j) = c'x(j)) and Q = diag(P_N, 0), so
    // the message is a 2 × 2 one on x: S = (I + Ω'P_N)⁻¹ Ω', Ω_{j−1} = [A'SA 0; 0 0], ω_{j−1} = [A'(σ − S B u); 0].
    Eigen::Matrix2d Om = s.Omega.topLeftCorner<2, 2>();
    Eigen::Vector2d om = s.omega.head<2>();
    if (s.dim == 1) {
      const Eigen::Vector2d c = h_.head<2>();
      Om += s.lambda(0, 0) * c * c.transpose();
      om += s.eta(0) * c;
    }
    prev.Omega.setZero();
    prev.omega.setZero();
    if (Om.isZero(0.0) && om.isZero(0.0)) return;
    const Eigen::Matrix2d A = s.F.topLeftCorner<2, 2>();
    const Eigen::Matrix2d M = (Eigen::Matrix2d::Identity() + Om * s.Q.topLeftCorner<2, 2>()).inverse();
    Eigen::Matrix2d S = M * Om;
    S = 0.5 * (S + S.transpose()).eval();
    Eigen::Matrix2d AS = A.transpose() * S * A;
    prev.Omega.topLeftCorner<2, 2>() = 0.5 * (AS + AS.transpose());
    prev.omega.head<2>() = A.transpose() * (M * om - S * s.b.head<2>());
    return;
  }
  Mat3 Om = s.Omega;
  Vec3 om = s.omega;
  {
    Mat23 H;
    H.row(0) << 0, 0, 1;
    H.row(1) = h_.transpose();
    Om += H.transpose() * s.lambda * H;
    om += H.transpose() * s.eta;
  }
  if (Om.isZero(0.0) && om.isZero(0.0)) {
    prev.Omega.setZero();
    prev.omega.setZero();
    return;
  }
  // ∫ N(z'; F z + b, Q) exp(−½ z''Ω'z' + ω''z') dz' ∝ exp(−½ μ'Sμ + σ'μ), μ = F z + b,
  // S = (I + Ω'Q)⁻¹ Ω', σ = (I + Ω'Q)⁻¹ ω'.
  const Mat3 M = (Mat3::Identity() + Om * s.Q).inverse();
  Mat3 S = M * Om;
  Symmetrize(S);
  const Vec3 sig = M * om;
  prev.Omega = s.F.transpose() * S * s.F;
  Symmetrize(prev.Omega);
  prev.omega = s.F.transpose() * (sig - S * s.b);
}

StepReport WindowEpFilter::Step(const models::LinearStateSpace& model, const Eigen::Ref<const Eigen::VectorXd>& u,
                                double y) {
  if (!model.FitsStep(2, u) || !(y == -1.0 || y == 0.0 || y == 1.0)) {
    return {StepStatus::kRejectedInvalid};
  }
  // A change of reading: the wedge of (s(k−1), s(k)) takes over the reading of step k−1 if that step's
  // site is a 1-D reading still inside the window after this step (W ≥ 2).
  const bool takeover = options_.window >= 2 && have_prev_ && y != y_prev_ && count_ >= 1 && At(count_ - 1).dim == 1;
  if (takeover) {
    Slot& p = At(count_ - 1);
    p.dim = 0;
    p.lambda.setZero();
    p.eta.setZero();
    Filtered(p);
  }
  // Append step k: transition, site.
  Slot& s = At(count_);
  ++count_;
  s.F.setZero();
  s.F.topLeftCorner<2, 2>() = model.A;
  s.F.block<1, 2>(2, 0) = h_.head<2>().transpose();
  s.Q.setZero();
  s.Q.topLeftCorner<2, 2>() = model.process_noise;
  s.b.setZero();
  if (model.num_inputs() > 0) s.b.head<2>().noalias() = model.B * u;
  s.lambda.setZero();
  s.eta.setZero();
  s.last_mean.setConstant(kNaN);
  s.last_cov.setConstant(kNaN);
  s.Omega.setZero();
  s.omega.setZero();
  s.bounds.setZero();
  s.sides.setOnes();
  if (takeover) {
    const ReadingChangeRegion region = ThresholdChangeRegion(threshold_, y_prev_, y);
    s.dim = 2;
    s.bounds = region.bounds;
    s.sides = region.sides;
  } else {
    s.dim = 1;
    s.lo = y > 0 ? threshold_ : (y < 0 ? -kInfinity : -threshold_);
    s.hi = y > 0 ? kInfinity : (y < 0 ? -threshold_ : threshold_);
  }
  // Freeze the sites that leave the window into the filtering prior (their last EP fit).
  while (count_ > options_.window) {
    base_m_ = At(0).filt_m;
    base_P_ = At(0).filt_P;
    head_ = (head_ + 1) % capacity_;
    --count_;
  }
  if (count_ == 1)
    Forward(s, base_m_, base_P_);
  else
    Forward(s, At(count_ - 2).filt_m, At(count_ - 2).filt_P);
  s.filt_m = s.pred_m;
  s.filt_P = s.pred_P;
  // The new site's first fit (the assumed-density step, β = 0). If it is the identity (bounds > 8.5 sd
  // away) and no site was taken over, no cavity of the window changes (β_j of the older slots gains
  // nothing), so the fixed point of the previous step is still one: no sweep is needed (exact).
  const double first = Refit(s);
  if (first < 0) ++failures_;
  Filtered(s);
  if (!takeover && s.lambda.isZero(0.0) && s.eta.isZero(0.0)) {
    last_sweeps_ = 0;
    last_converged_ = true;
    y_prev_ = y;
    have_prev_ = true;
    return {StepStatus::kUpdated};
  }

  // EP sweeps: backward pass with refits (fresh β, stored α⁻), then a forward pass of the messages α.
  last_converged_ = false;
  const int L = count_;
  for (last_sweeps_ = 1; last_sweeps_ <= options_.max_sweeps; ++last_sweeps_) {
    double change = 0;
    int first_changed = L;  // oldest slot whose site this pass changed
    for (int i = L - 1; i >= 0; --i) {
      Slot& si = At(i);
      if (i == L - 1) {
        si.Omega.setZero();
        si.omega.setZero();
      }
      const Eigen::Matrix2d lambda = si.lambda;
      const Eigen::Vector2d eta = si.eta;
      const double c = Refit(si);
      if (c < 0)
        ++failures_;
      else
        change = std::max(change, c);
      if (si.lambda != lambda || si.eta != eta) first_changed = i;
      if (i > 0) Backward(si, At(i - 1));
    }
    if (change <= options_.tolerance) last_converged_ = true;
    // Forward pass: messages only (the sites are refitted once per sweep, in the backward pass, where
    // the new information enters; the fixed point is the same, the erf / Owen's T evaluations halve).
    // α_j depends on the sites ≤ j only, so the messages older than the oldest changed site stand (exact).
    for (int i = first_changed; i < L; ++i) {
      Slot& si = At(i);
      if (i == 0)
        Forward(si, base_m_, base_P_);
      else
        Forward(si, At(i - 1).filt_m, At(i - 1).filt_P);
      Filtered(si);
    }
    if (last_converged_) break;
  }
  last_sweeps_ = std::min(last_sweeps_, options_.max_sweeps);
  y_prev_ = y;
  have_prev_ = true;
  return {StepStatus::kUpdated};
}

Eigen::Vector2d WindowEpFilter::mean() const {
  return count_ > 0 ? Eigen::Vector2d(At(count_ - 1).filt_m.head<2>()) : Eigen::Vector2d(base_m_.head<2>());
}

Eigen::Matrix2d WindowEpFilter::covariance() const {
  return count_ > 0 ? Eigen::Matrix2d(At(count_ - 1).filt_P.topLeftCorner<2, 2>())
                    : Eigen::Matrix2d(base_P_.topLeftCorner<2, 2>());
}

void WindowEpFilter::SmoothedMarginal(int lag, Eigen::Vector2d& mean, Eigen::Matrix2d& covariance) const {
  IDENT_REQUIRE(lag >= 0 && lag < count_, "WindowEpFilter::SmoothedMarginal: lag = {}; need 0 <= lag < {}", lag,
                count_);
  const Slot& s = At(count_ - 1 - lag);
  // α_j · β_j (moment form).
  const Mat3 P = (Mat3::Identity() + s.filt_P * s.Omega).inverse() * s.filt_P;
  const Vec3 m = s.filt_m + P * (s.omega - s.Omega * s.filt_m);
  mean = m.head<2>();
  covariance = 0.5 * (P.topLeftCorner<2, 2>() + P.topLeftCorner<2, 2>().transpose());
}

}  // namespace ident
