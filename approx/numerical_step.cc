#include "approx/numerical_step.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <vector>

#include <boost/math/quadrature/sinh_sinh.hpp>
#include <boost/math/tools/minima.hpp>

#include "common/dense_decompositions.h"
#include "common/error.h"

namespace ident::approx {
namespace {

// t'Vt with t = (−1, θ), written out so that it allocates nothing (it runs in the innermost loops).
double QuadForm(const Eigen::MatrixXd& V, const Eigen::VectorXd& theta) {
  double q = V(0, 0);
  for (Eigen::Index i = 0; i < theta.size(); ++i) {
    q -= theta(i) * (V(i + 1, 0) + V(0, i + 1));
    for (Eigen::Index j = 0; j < theta.size(); ++j) q += theta(i) * V(i + 1, j + 1) * theta(j);
  }
  return q;
}

struct Frame {  // centre and widths of the class member in Θ
  Eigen::VectorXd centre, width;
};
Frame FrameOf(const Eigen::MatrixXd& V) {
  const Eigen::Index rho = V.rows() - 1;
  const Eigen::MatrixXd Vz = V.bottomRightCorner(rho, rho);
  const Eigen::LDLT<Eigen::MatrixXd> ldlt = dense::Ldlt(Vz);
  Frame f;
  f.centre = ldlt.solve(V.bottomLeftCorner(rho, 1));
  const double Dy = V(0, 0) - V.col(0).tail(rho).dot(f.centre);
  f.width = (ldlt.solve(Eigen::MatrixXd::Identity(rho, rho)).diagonal() * std::max(Dy, 1e-300)).cwiseSqrt();
  return f;
}

// Nelder–Mead on f: R^n → R from x0 with initial step `step`. Its work vectors are allocated once.
template <class F>
double NelderMead(const F& f, Eigen::VectorXd x0, double step, int iterations) {
  const Eigen::Index n = x0.size();
  std::vector<Eigen::VectorXd> x(n + 1, x0);
  std::vector<double> fx(n + 1);
  for (Eigen::Index i = 0; i < n; ++i) x[i + 1](i) += step;
  for (Eigen::Index i = 0; i <= n; ++i) fx[i] = f(x[i]);
  std::vector<int> idx(n + 1);
  Eigen::VectorXd c(n), xr(n), xe(n), xc(n);
  for (int it = 0; it < iterations; ++it) {
    for (int i = 0; i <= n; ++i) idx[i] = i;
    std::sort(idx.begin(), idx.end(), [&](int a, int b) { return fx[a] < fx[b]; });
    const int best = idx[0], worst = idx[n], second = idx[n - 1];
    if (std::abs(fx[worst] - fx[best]) <= 1e-15 * (1 + std::abs(fx[best]))) break;
    c.setZero();
    for (int i = 0; i < n; ++i) c += x[idx[i]] / static_cast<double>(n);
    xr = c + (c - x[worst]);
    const double fr = f(xr);
    if (fr < fx[best]) {
      xe = c + 2 * (c - x[worst]);
      const double fe = f(xe);
      if (fe < fr)
        x[worst] = xe, fx[worst] = fe;
      else
        x[worst] = xr, fx[worst] = fr;
    } else if (fr < fx[second]) {
      x[worst] = xr, fx[worst] = fr;
    } else {
      xc = c + 0.5 * (x[worst] - c);
      const double fc = f(xc);
      if (fc < fx[worst]) {
        x[worst] = xc, fx[worst] = fc;
      } else {  // shrink towards the best point
        for (int i = 0; i <= n; ++i)
          if (i != best) x[i] = x[best] + 0.5 * (x[i] - x[best]), fx[i] = f(x[i]);
      }
    }
  }
  return *std::min_element(fx.begin(), fx.end());
}

double LogIntegral(double nu, const Eigen::MatrixXd& V, const LogShapeFn& log_shape, int delta) {
  const Eigen::Index rho = V.rows() - 1;
  const Frame fr = FrameOf(V);
  // Integrand in (σ = log ω, u): s(Θ̂ + w∘u, e^σ) e^{σ(1−δ/2)} Π w_i; shift by its peak over σ at u = 0.
  Eigen::VectorXd theta(rho);  // work vector of log_f, which the quadratures call millions of times
  auto log_f = [&](double sigma, const Eigen::VectorXd& u) {
    theta = fr.centre + fr.width.cwiseProduct(u);
    return log_shape(nu, V, theta, std::exp(sigma)) + sigma * (1 - delta / 2.0);
  };
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(rho);
  double s_peak = 0, peak = -std::numeric_limits<double>::infinity();
  for (double sg = -60; sg <= 60; sg += 0.25)
    if (const double v = log_f(sg, zero); v > peak) peak = v, s_peak = sg;
  // exp(log f − peak), with 0 where the shape underflows or overflows (the far tails sinh–sinh samples).
  auto f = [&](double sigma, const Eigen::VectorXd& u) {
    if (!(std::abs(sigma) < 700) || !u.allFinite()) return 0.0;
    const double v = log_f(sigma, u) - peak;
    return std::isfinite(v) ? std::exp(v) : 0.0;
  };
  // At most 7 halvings of the step per level (Boost's default is 15). The criterion is relative, so the inner
  // integrals at far-tail outer nodes, whose values are negligible against the peak, refine to the cap, and
  // every further halving doubles their integrand calls without changing the result
  // (tests/approx/numerical_step_test.cc checks it against the closed forms at ρ = 1 and 2).
  // 7 halvings are a step of 1/128 in the double-exponential variable: enough for the smooth, centred and
  // scaled integrand below.
  boost::math::quadrature::sinh_sinh<double> q(7);
  const double tol = 1e-11;
  auto inner = [&](double sigma) {
    Eigen::VectorXd u(rho);
    if (rho == 1) {
      return q.integrate(
          [&](double a) {
            u << a;
            return f(sigma, u);
          },
          tol);
    }
    return q.integrate(
        [&](double a) {
          return q.integrate(
              [&](double b) {
                u << a, b;
                return f(sigma, u);
              },
              tol);
        },
        tol);
  };
  const double I = q.integrate([&](double ds) { return inner(s_peak + ds); }, tol);
  return peak + std::log(I) + fr.width.array().log().sum();
}

}  // namespace

double StudentShape::operator()(double nu, const Eigen::MatrixXd& V, const Eigen::VectorXd& theta, double omega) const {
  return nu / 2 * std::log(omega) - (k + 1) / 2 * nu * std::log1p(omega * QuadForm(V, theta));
}

double GaussianShape::operator()(double nu, const Eigen::MatrixXd& V, const Eigen::VectorXd& theta,
                                 double omega) const {
  return nu / 2 * std::log(omega) - omega * nu * QuadForm(V, theta) / 2;
}

OneSidedStepResult NumericalEvaluate(const NormalisedStatistics& s, const Eigen::VectorXd& h, double beta,
                                     const LogModelFn& log_model, const LogShapeFn& log_shape, int delta) {
  const Eigen::Index rho = s.V.rows() - 1;
  IDENT_REQUIRE(rho >= 1 && rho <= 2 && s.V.cols() == rho + 1, "numerical step: V is {}x{}; need rho = 1 or 2",
                s.V.rows(), s.V.cols());
  IDENT_REQUIRE(h.size() == rho + 1, "numerical step: h has {} entries; need {}", h.size(), rho + 1);
  IDENT_REQUIRE(beta > 0 && beta < 1, "numerical step: beta = {}; need 0 < beta < 1", beta);
  OneSidedStepResult r{RankOneCandidate(s, h, beta), beta, 0, 0};
  // essinf over w = (Θ, log ω) of the ratio m·l(t−1)/s(t), in the prior's frame.
  const Frame fr = FrameOf(s.V);
  Eigen::VectorXd u(rho), theta(rho);       // work vectors of F
  auto F = [&](const Eigen::VectorXd& x) {  // x = (u, σ)
    u = x.head(rho).cwiseMax(-30).cwiseMin(30);
    const double sigma = std::clamp(x(rho), -40.0, 40.0);
    theta = fr.centre + fr.width.cwiseProduct(u);
    const double w = std::exp(sigma);
    return log_model(h, theta, w) + log_shape(s.nu, s.V, theta, w) - log_shape(r.stats.nu, r.stats.V, theta, w);
  };
  std::vector<std::pair<double, Eigen::VectorXd>> grid;
  Eigen::VectorXd x(rho + 1);
  const int nu_pts = rho == 1 ? 61 : 21;
  grid.reserve(static_cast<std::size_t>(nu_pts) * (rho == 1 ? 1 : nu_pts) * 41);
  for (int i = 0; i < nu_pts; ++i)
    for (int j = 0; j < (rho == 1 ? 1 : nu_pts); ++j)
      for (int l = 0; l <= 40; ++l) {
        x(0) = -30 + 60.0 * i / (nu_pts - 1);
        if (rho == 2) x(1) = -30 + 60.0 * j / (nu_pts - 1);
        x(rho) = -40 + 2.0 * l;
        grid.emplace_back(F(x), x);
      }
  std::partial_sort(grid.begin(), grid.begin() + 4, grid.end(),
                    [](const auto& a, const auto& b) { return a.first < b.first; });
  double best = grid[0].first;
  for (int i = 0; i < 4; ++i) best = std::min(best, NelderMead(F, grid[i].second, 0.5, 3000));
  r.log_gamma = best;
  r.log_integral = LogIntegral(r.stats.nu, r.stats.V, log_shape, delta);
  return r;
}

OneSidedStepResult NumericalStep(const NormalisedStatistics& s, const Eigen::VectorXd& h, const LogModelFn& log_model,
                                 const LogShapeFn& log_shape, int delta) {
  auto g = [&](double log_beta) {
    return -NumericalEvaluate(s, h, std::exp(log_beta), log_model, log_shape, delta).objective();
  };
  const int n = 48;
  const double lo = std::log(1e-9), hi = std::log(1 - 1e-6);
  int arg = 0;
  double top = std::numeric_limits<double>::infinity();
  for (int i = 0; i <= n; ++i)
    if (const double v = g(lo + (hi - lo) * i / n); v < top) top = v, arg = i;
  const double a = lo + (hi - lo) * std::max(arg - 1, 0) / n, b = lo + (hi - lo) * std::min(arg + 1, n) / n;
  const auto [lb, val] = boost::math::tools::brent_find_minima(g, a, b, 40);
  (void)val;
  return NumericalEvaluate(s, h, std::exp(lb), log_model, log_shape, delta);
}

}  // namespace ident::approx
