#include "ident/density/logconcave_mle.h"

#include <algorithm>
#include <cmath>

#include "common/error.h"

namespace ident::approx {
namespace {

// J(r, s) = int_0^1 exp((1-t) r + t s) dt and its first and second partial derivatives [DHR sec. 3]:
//   Jr = int (1-t) e, Js = int t e, Jrr = int (1-t)^2 e, Jrs = int t (1-t) e, Jss = int t^2 e.
struct JValues {
  double J, Jr, Js, Jrr, Jrs, Jss;
};

// j_k(d) = int_0^1 t^k e^{t d} dt for d <= 0 (k = 0, 1, 2): Taylor series sum_m d^m / (m! (m+k+1)) for
// |d| < 1 (the closed forms cancel there), closed forms otherwise.
void SmallJ(double d, double* j0, double* j1, double* j2) {
  if (std::abs(d) < 1.0) {
    // Terms fall like |d|^m / m!; stop once they no longer change s0 (at most 30 terms for |d| < 1).
    double term = 1, s0 = 0, s1 = 0, s2 = 0;
    for (int m = 0; m < 30; ++m) {
      s0 += term / (m + 1);
      s1 += term / (m + 2);
      s2 += term / (m + 3);
      term *= d / (m + 1);
      if (std::abs(term) < 1e-17 * s2) break;
    }
    *j0 = s0, *j1 = s1, *j2 = s2;
    return;
  }
  const double e = std::exp(d);
  *j0 = (e - 1) / d;
  *j1 = (e * (d - 1) + 1) / (d * d);
  *j2 = (e * (d * d - 2 * d + 2) - 2) / (d * d * d);
}

JValues Jfun(double r, double s) {
  const bool swap = s > r;  // expand around the larger end so that exp never overflows
  const double base = swap ? s : r, d = swap ? r - s : s - r;
  double j0, j1, j2;
  SmallJ(d, &j0, &j1, &j2);
  const double e = std::exp(base);
  JValues v;
  v.J = e * j0;
  const double near = e * (j0 - j1), far = e * j1;  // int (1-t) e, int t e  (t from `base`)
  const double near2 = e * (j0 - 2 * j1 + j2), far2 = e * j2, mixed = e * (j1 - j2);
  v.Jr = swap ? far : near;
  v.Js = swap ? near : far;
  v.Jrr = swap ? far2 : near2;
  v.Jss = swap ? near2 : far2;
  v.Jrs = mixed;
  return v;
}

// J(r, s) and Jr(r, s) given er = e^r, es = e^s (each exp computed once per data point):
//   J = (es - er) / d,  Jr = (es - er - d er) / d^2  (d = s - r), Taylor series in d for |d| < 0.01.
inline void SegmentIntegrals(double r, double s, double er, double es, double* J, double* Jr) {
  const double d = s - r;
  if (std::abs(d) < 1e-2) {
    // J/er = sum_m d^m/(m+1)!,  Jr/er = sum_m d^m/(m+2)!  (Horner; the d^7 terms are below 1e-18)
    const double j0 = 1 + d * (1. / 2 + d * (1. / 6 + d * (1. / 24 + d * (1. / 120 + d * (1. / 720 + d / 5040)))));
    const double jr =
        1. / 2 + d * (1. / 6 + d * (1. / 24 + d * (1. / 120 + d * (1. / 720 + d * (1. / 5040 + d / 40320)))));
    *J = er * j0;
    *Jr = er * jr;
    return;
  }
  *J = (es - er) / d;
  *Jr = (es - er - d * er) / (d * d);
}

class ActiveSet {
 public:
  ActiveSet(const Eigen::VectorXd& x, const Eigen::VectorXd& w, const LogConcaveMleOptions& o)
      : x_(x), w_(w), o_(o), m_(static_cast<int>(x.size())) {}

  // Newton's method for the knot values eta (knot set kn), starting at phi[kn]; returns phi at all points.
  Eigen::VectorXd LocalMle(const std::vector<int>& kn, const Eigen::VectorXd& phi_start) const {
    const int K = static_cast<int>(kn.size());
    Eigen::VectorXd c = Eigen::VectorXd::Zero(K), eta(K), delta(K - 1);
    for (int a = 0; a < K; ++a) {
      eta(a) = phi_start(kn[a]);
      c(a) += w_(kn[a]);
    }
    for (int a = 0; a + 1 < K; ++a) {
      delta(a) = x_(kn[a + 1]) - x_(kn[a]);
      for (int j = kn[a] + 1; j < kn[a + 1]; ++j) {
        const double lambda = (x_(j) - x_(kn[a])) / delta(a);
        c(a) += w_(j) * (1 - lambda);
        c(a + 1) += w_(j) * lambda;
      }
    }
    auto objective = [&](const Eigen::VectorXd& e) {
      double L = c.dot(e);
      for (int a = 0; a + 1 < K; ++a) L -= delta(a) * Jfun(e(a), e(a + 1)).J;
      return L;
    };
    Eigen::VectorXd g(K), diag(K), off(std::max(K - 1, 1)), step(K), trial(K);
    double L = objective(eta);
    int fine_steps = 0;
    for (int it = 0; it < 200; ++it) {
      g = c;
      diag.setZero();
      for (int a = 0; a + 1 < K; ++a) {  // -Hessian (tridiagonal, positive definite)
        const JValues v = Jfun(eta(a), eta(a + 1));
        g(a) -= delta(a) * v.Jr;
        g(a + 1) -= delta(a) * v.Js;
        diag(a) += delta(a) * v.Jrr;
        diag(a + 1) += delta(a) * v.Jss;
        off(a) = delta(a) * v.Jrs;
      }
      // Thomas algorithm for (-H) step = g.
      step = g;
      for (int a = 1; a < K; ++a) {
        const double f = off(a - 1) / diag(a - 1);
        diag(a) -= f * off(a - 1);
        step(a) -= f * step(a - 1);
      }
      step(K - 1) /= diag(K - 1);
      for (int a = K - 2; a >= 0; --a) step(a) = (step(a) - off(a) * step(a + 1)) / diag(a);
      const double decrement = g.dot(step);
      // Newton decrement g'(-H)^-1 g = twice the predicted gain in L. Below 1e-10 the full step is taken
      // without line search (quadratic convergence; L itself cannot resolve such gains in rounding),
      // and at most 3 such steps are needed to reach rounding level.
      if (!(decrement > 1e-26)) break;
      if (decrement < 1e-10) {
        eta += step;
        L = objective(eta);
        if (++fine_steps >= 3) break;
        continue;
      }
      double t = 1;
      for (; t > 1e-12; t *= 0.5) {
        trial = eta + t * step;
        const double Lt = objective(trial);
        if (Lt >= L + 1e-4 * t * decrement) {
          L = Lt;
          eta = trial;
          break;
        }
      }
      if (t <= 1e-12) break;
    }
    return Expand(kn, eta);
  }

  Eigen::VectorXd Expand(const std::vector<int>& kn, const Eigen::VectorXd& eta) const {
    Eigen::VectorXd phi(m_);
    for (size_t a = 0; a + 1 < kn.size(); ++a) {
      const double delta = x_(kn[a + 1]) - x_(kn[a]);
      for (int j = kn[a]; j <= kn[a + 1]; ++j) {
        const double lambda = (x_(j) - x_(kn[a])) / delta;
        phi(j) = (1 - lambda) * eta(a) + lambda * eta(a + 1);
      }
    }
    return phi;
  }

  // Slope change (right slope - left slope) of phi at each interior knot; > 0 breaks concavity.
  Eigen::VectorXd Convexity(const std::vector<int>& kn, const Eigen::VectorXd& phi) const {
    const int K = static_cast<int>(kn.size());
    Eigen::VectorXd conv = Eigen::VectorXd::Zero(K);
    for (int a = 1; a + 1 < K; ++a) {
      const double left = (phi(kn[a]) - phi(kn[a - 1])) / (x_(kn[a]) - x_(kn[a - 1]));
      const double right = (phi(kn[a + 1]) - phi(kn[a])) / (x_(kn[a + 1]) - x_(kn[a]));
      conv(a) = right - left;
    }
    return conv;
  }

  LogConcaveMle Run(int n) {
    std::vector<int> kn = {0, m_ - 1};
    Eigen::VectorXd phi = Eigen::VectorXd::Constant(m_, -std::log(x_(m_ - 1) - x_(0)));  // uniform start
    phi = LocalMle(kn, phi);
    const double range = x_(m_ - 1) - x_(0);
    int iterations = 0;
    // Knots are added in rounds: between each pair of neighbouring knots the point with the largest D_j > 0
    // (a local maximum of D: adding it is an ascent direction, [DHR] sec. 3.2), all at once, then the
    // Newton/step-back loop restores concavity, dropping knots as needed. A round that keeps none of its
    // new knots is repeated with the single best one (the one-knot algorithm of [DHR], which stops when that
    // knot is rejected at once).
    bool single = false;
    std::vector<int> added, before;
    while (iterations < o_.max_iterations) {
      const Eigen::VectorXd D = DirectionalDerivatives(x_, w_, phi);
      const int best = NewKnots(D, kn, range, &added);
      if (o_.on_iteration) o_.on_iteration(iterations, best < 0 ? 0.0 : D(best) / range);
      if (best < 0) break;
      if (single) added.assign(1, best);
      ++iterations;
      before = kn;
      for (int j : added) kn.insert(std::upper_bound(kn.begin(), kn.end(), j), j);
      if (RestoreConcavity(single, best, kn, phi, iterations)) break;
      // A round that kept none of its knots: the next one adds the single best knot.
      single = !single && kn == before;
    }
    return Result(n, kn, phi, iterations);
  }

  // The candidate knots of a round into *added: between each pair of neighbouring knots kn the point with the
  // largest D_j above tolerance · range; returns the best of them (−1: none).
  int NewKnots(const Eigen::VectorXd& D, const std::vector<int>& kn, double range, std::vector<int>* added) const {
    added->clear();
    int best = -1;
    for (size_t a = 0; a + 1 < kn.size(); ++a) {
      int local = -1;
      for (int j = kn[a] + 1; j < kn[a + 1]; ++j)
        if (D(j) > o_.tolerance * range && (local < 0 || D(j) > D(local))) local = j;
      if (local < 0) continue;
      added->push_back(local);
      if (best < 0 || D(local) > D(best)) best = local;
    }
    return best;
  }

  // The Newton/step-back loop after knots were added: the local MLE on kn, stepped back towards the concave
  // phi and with the knots that turn linear dropped until it is concave; phi and kn become the result. True
  // if the algorithm stalls: a single new knot (`best`) rejected at once, no knot dropped, or the iteration
  // limit reached (each step back counts as an iteration).
  bool RestoreConcavity(bool single, int best, std::vector<int>& kn, Eigen::VectorXd& phi, int& iterations) const {
    for (;;) {
      const Eigen::VectorXd phi_new = LocalMle(kn, phi);
      const Eigen::VectorXd conv_new = Convexity(kn, phi_new);
      if (conv_new.maxCoeff() <= 0) {
        phi = phi_new;
        return false;
      }
      // Step back from the concave phi towards phi_new until the first knot turns linear [DHR sec. 3.2].
      // phi is concave: a positive slope change at a knot is rounding (at a new knot phi is linear).
      const Eigen::VectorXd conv_old = Convexity(kn, phi).cwiseMin(0.0);
      double lambda = 1;
      for (int a = 0; a < conv_new.size(); ++a)
        if (conv_new(a) > 0) lambda = std::min(lambda, conv_old(a) / (conv_old(a) - conv_new(a)));
      phi = (1 - lambda) * phi + lambda * phi_new;
      std::vector<int> kept;
      for (int a = 0; a < static_cast<int>(kn.size()); ++a) {
        const bool drop = conv_new(a) > 0 && conv_old(a) / (conv_old(a) - conv_new(a)) <= lambda * (1 + 1e-12);
        if (!drop) kept.push_back(kn[a]);
      }
      if (single && lambda == 0 && kept.size() + 1 == kn.size() &&
          std::find(kept.begin(), kept.end(), best) == kept.end()) {
        kn = kept;  // the new knot is rejected at once: D(best) is at rounding level
        return true;
      }
      if (kept.size() == kn.size() || ++iterations >= o_.max_iterations) {
        // No knot dropped: NaN convexities at scales double cannot resolve (samples from 6e-322 to
        // 2.5e260) would loop here for ever. FitLogConcaveMle's KKT check refuses the result.
        return true;
      }
      kn = kept;
    }
  }

  // The estimate with knots kn and log-density phi at the points, from a sample of n.
  LogConcaveMle Result(int n, const std::vector<int>& kn, const Eigen::VectorXd& phi, int iterations) const {
    LogConcaveMle mle;
    mle.n = n;
    mle.x = x_;
    mle.weights = w_;
    mle.phi = phi;
    mle.knot_index = kn;
    mle.knots.resize(kn.size());
    mle.knot_phi.resize(kn.size());
    for (size_t a = 0; a < kn.size(); ++a) {
      mle.knots(a) = x_(kn[a]);
      mle.knot_phi(a) = phi(kn[a]);
    }
    mle.loglik = n * w_.dot(phi);
    mle.iterations = iterations;
    return mle;
  }

  // D_j = int_{x_1}^{x_j} (F_hat - F_n)(r) dr at every data point, with
  //   F_hat(x_{j+1}) = F_hat(x_j) + delta J(phi_j, phi_{j+1}),
  //   int_{x_j}^{x_{j+1}} F_hat = delta F_hat(x_j) + delta^2 Jr(phi_j, phi_{j+1}).
  static Eigen::VectorXd DirectionalDerivatives(const Eigen::VectorXd& x, const Eigen::VectorXd& w,
                                                const Eigen::VectorXd& phi) {
    const int m = static_cast<int>(x.size());
    Eigen::VectorXd D(m);
    double F = 0, IF = 0, Fn = 0, IFn = 0, e_next = std::exp(phi(0));
    D(0) = 0;
    for (int j = 0; j + 1 < m; ++j) {
      const double delta = x(j + 1) - x(j), e = e_next;
      e_next = std::exp(phi(j + 1));
      double J, Jr;
      SegmentIntegrals(phi(j), phi(j + 1), e, e_next, &J, &Jr);
      IF += delta * F + delta * delta * Jr;
      F += delta * J;
      Fn += w(j);
      IFn += delta * Fn;
      D(j + 1) = IF - IFn;
    }
    return D;
  }

 private:
  const Eigen::VectorXd& x_;
  const Eigen::VectorXd& w_;
  const LogConcaveMleOptions& o_;
  const int m_;
};

}  // namespace

LogConcaveMle FitLogConcaveMle(const std::vector<double>& samples, const LogConcaveMleOptions& options) {
  IDENT_REQUIRE(options.max_iterations >= 1, "max_iterations = {}; need >= 1", options.max_iterations);
  IDENT_REQUIRE(options.tolerance > 0 && options.tolerance < 1e-3, "tolerance = {}; need 0 < tolerance < 1e-3",
                options.tolerance);
  for (size_t i = 0; i < samples.size(); ++i)
    IDENT_REQUIRE(std::isfinite(samples[i]), "sample {} = {} is not finite", i, samples[i]);
  std::vector<double> sorted = samples;
  std::sort(sorted.begin(), sorted.end());
  std::vector<double> xs, counts;
  for (double v : sorted) {
    if (xs.empty() || v != xs.back()) {
      xs.push_back(v);
      counts.push_back(0);
    }
    counts.back() += 1;
  }
  IDENT_REQUIRE(xs.size() >= 2, "log-concave MLE needs at least 2 distinct sample values, got {}", xs.size());
  IDENT_REQUIRE(std::isfinite(xs.back() - xs.front()),
                "samples span [{}, {}], a range beyond the largest double; rescale them", xs.front(), xs.back());
  const int n = static_cast<int>(samples.size());
  Eigen::VectorXd x = Eigen::Map<const Eigen::VectorXd>(xs.data(), xs.size());
  Eigen::VectorXd w = Eigen::Map<const Eigen::VectorXd>(counts.data(), counts.size()) / n;
  ActiveSet solver(x, w, options);
  LogConcaveMle mle = solver.Run(n);
  // Samples at scales double cannot resolve (e.g. subnormal spacings: a density beyond 1e308) leave
  // the active set short of the characterisation [DHR, Theorem 2.4]; refuse them rather than return
  // a wrong density. (A fuzz finding: samples {0, 5e-324, 1e-320, 2e-310}.)
  const double range = x(x.size() - 1) - x(0);
  double min_gap = range;
  for (Eigen::Index j = 0; j + 1 < x.size(); ++j) min_gap = std::min(min_gap, x(j + 1) - x(j));
  const LogConcaveKkt kkt = CheckKkt(mle);
  IDENT_REQUIRE(mle.phi.allFinite() && std::isfinite(mle.loglik) && kkt.mass_error <= 1e-7 &&
                    kkt.max_directional_derivative <= 1e-7 * range && kkt.max_knot_residual <= 1e-7 * range,
                "samples: no log-concave MLE in double precision for samples spanning [{}, {}] with distinct values "
                "as close as {} (|int f - 1| = {:.1e}); rescale them",
                x(0), x(x.size() - 1), min_gap, kkt.mass_error);
  return mle;
}

double LogConcaveMle::LogDensity(double t) const {
  const int m = static_cast<int>(x.size());
  if (!(t >= x(0) && t <= x(m - 1))) return -models::kInfinity;
  const int j = std::clamp(static_cast<int>(std::upper_bound(x.data(), x.data() + m, t) - x.data()) - 1, 0, m - 2);
  const double lambda = (t - x(j)) / (x(j + 1) - x(j));
  return (1 - lambda) * phi(j) + lambda * phi(j + 1);
}

double LogConcaveMle::Cdf(double t) const {
  const int m = static_cast<int>(x.size());
  if (t <= x(0)) return 0;
  double F = 0;
  for (int j = 0; j + 1 < m; ++j) {
    const double delta = x(j + 1) - x(j);
    if (t < x(j + 1)) {  // partial segment [x_j, t]
      const double s = (t - x(j)) / delta;
      return F + s * delta * Jfun(phi(j), LogDensity(t)).J;
    }
    F += delta * Jfun(phi(j), phi(j + 1)).J;
  }
  return F;
}

models::Penalty LogConcaveMle::NegativeLogDensity() const { return models::Penalty::PiecewiseLinear(knots, -knot_phi); }

double LogConcaveMle::ConjugateOfNegativeLogDensity(double v) const {
  double best = -models::kInfinity;
  for (int a = 0; a < knots.size(); ++a) best = std::max(best, v * knots(a) + knot_phi(a));
  return best;
}

LogConcaveKkt CheckKkt(const LogConcaveMle& mle) {
  const int m = static_cast<int>(mle.x.size());
  LogConcaveKkt k;
  const Eigen::VectorXd D = ActiveSet::DirectionalDerivatives(mle.x, mle.weights, mle.phi);
  k.max_directional_derivative = D.maxCoeff();
  for (int a : mle.knot_index) k.max_knot_residual = std::max(k.max_knot_residual, std::abs(D(a)));
  double mass = 0;
  for (int j = 0; j + 1 < m; ++j) mass += (mle.x(j + 1) - mle.x(j)) * Jfun(mle.phi(j), mle.phi(j + 1)).J;
  k.mass_error = std::abs(mass - 1);
  for (int j = 1; j + 1 < m; ++j) {
    const double left = (mle.phi(j) - mle.phi(j - 1)) / (mle.x(j) - mle.x(j - 1));
    const double right = (mle.phi(j + 1) - mle.phi(j)) / (mle.x(j + 1) - mle.x(j));
    k.max_concavity_violation = std::max(k.max_concavity_violation, right - left);
  }
  return k;
}

}  // namespace ident::approx
