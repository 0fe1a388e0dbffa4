#include "ident/observers/truncated_gaussian_filter.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <utility>

#include <Eigen/LU>
#include <boost/math/distributions/normal.hpp>
#include <boost/math/special_functions/owens_t.hpp>

#include "common/dense_decompositions.h"
#include "common/error.h"
#include "models/truncated_bivariate_normal.h"

namespace ident {
namespace {

constexpr double kTgInf = std::numeric_limits<double>::infinity();
constexpr double kTgFarSd = 9.0;       // a bound this many sd away holds mass < 1.2e-19
constexpr double kTgMassFloor = 1e-8;  // inclusion–exclusion is accurate to ≈ 1e-15 absolute

using TgPolicy = boost::math::policies::policy<boost::math::policies::promote_double<false>>;

double TgPhi(double x) { return 0.5 * std::erfc(-x / std::numbers::sqrt2); }
double TgTail(double x) { return 0.5 * std::erfc(x / std::numbers::sqrt2); }  // Q(x) = P(X > x)
double TgDensity(double x) { return std::isfinite(x) ? std::exp(-0.5 * x * x) / std::sqrt(2 * std::numbers::pi) : 0.0; }

// Φ2(a, b; ρ) by Owen's T (Owen 1956, eq. (2.1)); a, b ≠ 0 (nudged by 1e-13: error < 1e-13 absolute).
double TgOwenCdf(double a, double b, double rho, double s) {
  if (a == 0) a = 1e-13;
  if (b == 0) b = 1e-13;
  const double alpha_a = (b - rho * a) / (a * s), alpha_b = (a - rho * b) / (b * s);
  const double beta = a * b > 0 ? 0.0 : 0.5;
  return 0.5 * TgPhi(a) + 0.5 * TgPhi(b) - boost::math::owens_t(a, alpha_a, TgPolicy()) -
         boost::math::owens_t(b, alpha_b, TgPolicy()) - beta;
}

// Unnormalised moments of standard normals (X, Y), correlation ρ, on the quadrant X > h, Y > k (h, k may be
// ±∞): L, L E[X], L E[Y], L E[X²], L E[Y²], L E[XY] (Tallis 1961; the formulas of
// models/truncated_bivariate_normal.h in linear space, so that they can be added and subtracted).
struct TgQuadrant {
  double l = 0, x = 0, y = 0, xx = 0, yy = 0, xy = 0;
};
TgQuadrant TgQuadrantMoments(double h, double k, double rho, double s) {
  TgQuadrant q;
  if (h == kTgInf || k == kTgInf) return q;
  const bool fh = std::isfinite(h), fk = std::isfinite(k);
  if (!fh && !fk)
    q.l = 1;
  else if (!fh)
    q.l = TgTail(k);
  else if (!fk)
    q.l = TgTail(h);
  else
    q.l = std::max(TgOwenCdf(-h, -k, rho, s), 0.0);
  const double ah = fh ? TgDensity(h) * (fk ? TgTail((k - rho * h) / s) : 1.0) : 0.0;
  const double ak = fk ? TgDensity(k) * (fh ? TgTail((h - rho * k) / s) : 1.0) : 0.0;
  const double f =
      fh && fk ? std::exp(-(h * h - 2 * rho * h * k + k * k) / (2 * s * s)) / (2 * std::numbers::pi * s) : 0.0;
  const double hah = fh ? h * ah : 0.0, kak = fk ? k * ak : 0.0;
  q.x = ah + rho * ak;
  q.y = ak + rho * ah;
  q.xx = q.l + hah + rho * rho * kak + rho * s * s * f;
  q.yy = q.l + kak + rho * rho * hah + rho * s * s * f;
  q.xy = rho * q.l + rho * hah + rho * kak + s * s * f;
  return q;
}

}  // namespace

RectangleMoments TruncatedBivariateRectangleMoments(const Eigen::Vector2d& mean, const Eigen::Matrix2d& covariance,
                                                    const Eigen::Vector2d& lo, const Eigen::Vector2d& hi) {
  RectangleMoments out;
  if (!mean.allFinite() || !covariance.allFinite() || lo.hasNaN() || hi.hasNaN()) return out;
  if (!(covariance(0, 0) > 0) || !(covariance(1, 1) > 0) || !(lo(0) < hi(0)) || !(lo(1) < hi(1))) return out;
  const Eigen::Vector2d sd(std::sqrt(covariance(0, 0)), std::sqrt(covariance(1, 1)));
  const double rho = 0.5 * (covariance(0, 1) + covariance(1, 0)) / (sd(0) * sd(1));
  if (!(std::abs(rho) < 1 - 1e-12)) return out;
  Eigen::Vector2d l, u;  // standardised bounds, far ones dropped
  for (int i = 0; i < 2; ++i) {
    l(i) = (lo(i) - mean(i)) / sd(i);
    u(i) = (hi(i) - mean(i)) / sd(i);
    if (l(i) < -kTgFarSd) l(i) = -kTgInf;
    if (u(i) > kTgFarSd) u(i) = kTgInf;
  }
  const bool one_bound = (l(0) == -kTgInf || u(0) == kTgInf) && (l(1) == -kTgInf || u(1) == kTgInf);
  if (one_bound) {
    // One Tallis quadrant (log-space, accurate far into the tails).
    Eigen::Vector2d bounds, sides;
    for (int i = 0; i < 2; ++i) {
      if (u(i) != kTgInf) {
        bounds(i) = hi(i);
        sides(i) = -1;
      } else if (l(i) != -kTgInf) {
        bounds(i) = lo(i);
        sides(i) = 1;
      } else {
        bounds(i) = -kTgInf;
        sides(i) = 1;
      }
    }
    if (bounds(0) == -kTgInf && bounds(1) == -kTgInf) {
      out.log_probability = 0;
      out.mean = mean;
      out.covariance = 0.5 * (covariance + covariance.transpose());
      out.ok = true;
      return out;
    }
    const auto t = models::TruncatedBivariateNormalMoments(mean, covariance, bounds, sides);
    if (!t.ok) return out;
    out.log_probability = t.log_probability;
    out.mean = t.mean;
    out.covariance = t.covariance;
    out.ok = true;
    return out;
  }
  // Inclusion–exclusion: 1{l1 < X < u1} 1{l2 < Y < u2} = Σ ± 1{X > ·, Y > ·} over the four corners.
  const double s = std::sqrt((1 - rho) * (1 + rho));
  TgQuadrant r;
  const double hs[2] = {l(0), u(0)}, ks[2] = {l(1), u(1)};
  for (int a = 0; a < 2; ++a) {
    for (int b = 0; b < 2; ++b) {
      const TgQuadrant q = TgQuadrantMoments(hs[a], ks[b], rho, s);
      const double sign = (a + b) % 2 == 0 ? 1.0 : -1.0;
      r.l += sign * q.l;
      r.x += sign * q.x;
      r.y += sign * q.y;
      r.xx += sign * q.xx;
      r.yy += sign * q.yy;
      r.xy += sign * q.xy;
    }
  }
  if (!(r.l >= kTgMassFloor)) return out;
  const double ex = r.x / r.l, ey = r.y / r.l;
  const double vx = r.xx / r.l - ex * ex, vy = r.yy / r.l - ey * ey, cxy = r.xy / r.l - ex * ey;
  if (!(vx > 0) || !(vy > 0) || !(cxy * cxy < vx * vy)) return out;
  out.log_probability = std::log(r.l);
  out.mean << mean(0) + sd(0) * ex, mean(1) + sd(1) * ey;
  out.covariance << covariance(0, 0) * vx, sd(0) * sd(1) * cxy, sd(0) * sd(1) * cxy, covariance(1, 1) * vy;
  out.ok = out.mean.allFinite() && out.covariance.allFinite();
  return out;
}

bool InvertTruncatedNormalMoments(double mean, double variance, double lo, double hi, double& a, double& v) {
  if (!(variance > 0) || !std::isfinite(mean) || !(lo < mean && mean < hi)) return false;
  if (lo == -kTgInf && hi == kTgInf) {
    a = mean;
    v = variance;
    return true;
  }
  const double scale = std::sqrt(variance);
  // Work in y = (x − mean)/scale: target mean 0, log sd 0. Unknowns (c, t): parent N(c, e^{2t}).
  const double ly = (lo - mean) / scale, uy = (hi - mean) / scale;
  struct Eval {
    bool ok = false;
    double r0 = 0, r1 = 0;  // residual: mean, ½ log var
    double j00 = 0, j01 = 0, j10 = 0, j11 = 0;
  };
  auto eval = [&](double c, double t) {
    Eval e;
    const double sd = std::exp(t);
    const double al = (ly - c) / sd, be = (uy - c) / sd;
    const auto z = models::StandardTruncatedMoments(al, be);
    if (!z.ok || !(z.variance > 0)) return e;
    const double pa =
        std::isfinite(al) ? std::exp(-0.5 * al * al - 0.5 * std::log(2 * std::numbers::pi) - z.log_normalizer) : 0.0;
    const double pb =
        std::isfinite(be) ? std::exp(-0.5 * be * be - 0.5 * std::log(2 * std::numbers::pi) - z.log_normalizer) : 0.0;
    const double mz = z.mean, e2 = z.variance + mz * mz;
    const double am = std::isfinite(al) ? pa * (mz - al) : 0.0, bm = std::isfinite(be) ? pb * (be - mz) : 0.0;
    const double ae2 = std::isfinite(al) ? pa * (e2 - al * al) : 0.0,
                 be2 = std::isfinite(be) ? pb * (be * be - e2) : 0.0;
    const double av = ae2 - 2 * mz * am, bv = be2 - 2 * mz * bm;
    const double aal = std::isfinite(al) ? al : 0.0, bbe = std::isfinite(be) ? be : 0.0;
    e.r0 = c + sd * mz;
    e.r1 = t + 0.5 * std::log(z.variance);
    // d/dc: dα = dβ = −1/sd; d/dt: dα = −α, dβ = −β.
    e.j00 = 1 - (am + bm);
    e.j01 = sd * mz - sd * (aal * am + bbe * bm);
    e.j10 = 0.5 * (-(av + bv) / sd) / z.variance;
    e.j11 = 1 + 0.5 * (-(aal * av + bbe * bv)) / z.variance;
    e.ok = std::isfinite(e.r0) && std::isfinite(e.r1) && std::isfinite(e.j00 + e.j01 + e.j10 + e.j11);
    return e;
  };
  double c = 0, t = 0;
  Eval e = eval(c, t);
  if (!e.ok) return false;
  double norm = std::hypot(e.r0, e.r1);
  for (int it = 0; it < 100 && norm > 1e-13; ++it) {
    const double det = e.j00 * e.j11 - e.j01 * e.j10;
    if (!(std::abs(det) > 0)) return false;
    const double dc = -(e.j11 * e.r0 - e.j01 * e.r1) / det, dt = -(-e.j10 * e.r0 + e.j00 * e.r1) / det;
    double step = 1;
    bool moved = false;
    for (int ls = 0; ls < 40; ++ls, step *= 0.5) {
      const double dtt = std::clamp(step * dt, -2.0, 2.0);
      const Eval n = eval(c + step * dc, t + dtt);
      if (n.ok && std::hypot(n.r0, n.r1) < norm) {
        c += step * dc;
        t += dtt;
        e = n;
        norm = std::hypot(e.r0, e.r1);
        moved = true;
        break;
      }
    }
    if (!moved || t > 30) break;
  }
  a = mean + scale * c;
  v = variance * std::exp(2 * t);
  return norm <= 1e-9;
}

TruncatedGaussianFilter::TruncatedGaussianFilter(const models::ThresholdSensor& sensor, const Eigen::Vector2d& mean,
                                                 const Eigen::Matrix2d& covariance)
    : threshold_(sensor.threshold()),
      pm_(mean),
      mean_(mean),
      pP_(covariance),
      cov_(covariance),
      lo_(-kTgInf),
      hi_(kTgInf) {
  IDENT_REQUIRE(sensor.num_states() == 2, "TruncatedGaussianFilter: the sensor reads {} states; need 2",
                sensor.num_states());
  IDENT_REQUIRE(mean.allFinite() && covariance.allFinite(),
                "TruncatedGaussianFilter: prior mean/covariance not finite");
  IDENT_REQUIRE(
      (covariance - covariance.transpose()).cwiseAbs().maxCoeff() <= 1e-12 * (1 + covariance.cwiseAbs().maxCoeff()),
      "TruncatedGaussianFilter: prior covariance not symmetric");
  IDENT_REQUIRE(dense::SymmetricEigen2x2(covariance).eigenvalues().minCoeff() > 0,
                "TruncatedGaussianFilter: prior covariance not positive definite");
  c_ = sensor.c().head<2>();
}

TruncatedGaussianFilter::TruncatedGaussianFilter(models::LinearStateSpace model, const models::ThresholdSensor& sensor,
                                                 const Eigen::Vector2d& mean, const Eigen::Matrix2d& covariance)
    : TruncatedGaussianFilter(sensor, mean, covariance) {
  model.Validate();
  IDENT_REQUIRE(model.num_states() == 2, "TruncatedGaussianFilter: the model has {} states; need 2",
                model.num_states());
  model_ = std::move(model);
  has_model_ = true;
}

StepReport TruncatedGaussianFilter::Update(const StateSpaceItem& item) {
  if (!has_model_) return {StepStatus::kRejectedInvalid};
  return Step(model_, item.u, item.y);
}

StepReport TruncatedGaussianFilter::Step(const models::LinearStateSpace& model,
                                         const Eigen::Ref<const Eigen::VectorXd>& u, double y) {
  if (!model.FitsStep(2, u) || !(y == -1.0 || y == 0.0 || y == 1.0)) {
    return {StepStatus::kRejectedInvalid};
  }
  const double T = threshold_;
  const double lo = y > 0 ? T : (y < 0 ? -kTgInf : -T);
  const double hi = y > 0 ? kTgInf : (y < 0 ? -T : T);
  const Eigen::Matrix2d A = model.A;
  Eigen::Vector2d mp = A * pm_;
  if (model.num_inputs() > 0) {
    const Eigen::Vector2d Bu = model.B * u;  // not `mp += B u`: Eigen's aliasing-safe temporary is heap-allocated
    mp += Bu;
  }
  Eigen::Matrix2d Pp = A * pP_ * A.transpose() + model.process_noise;
  Pp = 0.5 * (Pp + Pp.transpose()).eval();
  // s = (c'x(k−1), c'x(k)) under the parent.
  const Eigen::Vector2d Pc = pP_ * c_, Ppc = Pp * c_;
  Eigen::Vector2d mu_s(c_.dot(pm_), c_.dot(mp));
  Eigen::Matrix2d S;
  S << c_.dot(Pc), c_.dot(A * Pc), c_.dot(A * Pc), c_.dot(Ppc);
  Eigen::Matrix2d C;  // Cov(x(k), s)
  C.col(0) = A * Pc;
  C.col(1) = Ppc;
  const RectangleMoments t =
      TruncatedBivariateRectangleMoments(mu_s, S, Eigen::Vector2d(lo_, lo), Eigen::Vector2d(hi_, hi));
  Eigen::Vector2d mx;
  Eigen::Matrix2d Px;
  if (t.ok) {
    const Eigen::Matrix2d K = C * S.inverse();
    mx = mp + K * (t.mean - mu_s);
    Px = Pp - K * (S - t.covariance) * K.transpose();
  } else {
    // No mass under the approximation: fall back to the predicted parent restricted to the new interval.
    ++failures_;
    const double sm = c_.dot(mp), sv = c_.dot(Ppc);
    const auto t1 = models::TruncatedNormalMoments(sm, sv, lo, hi);
    mx = mp;
    Px = Pp;
    if (t1.ok) {
      const Eigen::Vector2d g = Ppc / sv;
      mx = mp + g * (t1.mean - sm);
      Px = Pp - g * g.transpose() * (sv - t1.variance);
    }
  }
  Px = 0.5 * (Px + Px.transpose()).eval();
  mean_ = mx;
  cov_ = Px;
  // Projection: the parent whose restriction to c'x ∈ (lo, hi) has moments (mx, Px).
  const double sm = c_.dot(mx), sv = c_.dot(Px * c_);
  double a = sm, v = sv;
  if (!InvertTruncatedNormalMoments(sm, sv, lo, hi, a, v)) {
    ++projection_failures_;
    if (!(v > 0) || !std::isfinite(v) || !std::isfinite(a)) {
      a = sm;
      v = sv;
    }
  }
  const Eigen::Vector2d g = Px * c_ / sv;
  pP_ = Px - g * g.transpose() * sv + g * g.transpose() * v;
  pP_ = 0.5 * (pP_ + pP_.transpose()).eval();
  pm_ = mx - g * (sm - a);
  lo_ = lo;
  hi_ = hi;
  return {StepStatus::kUpdated};
}

}  // namespace ident
