// Cauchy maximum likelihood in Θ and scale (CauchyMlRegression, ident/regression/batch_regression.h): the
// problem in the orthonormalised basis, its starts (elemental subsets, LTS concentration, least squares),
// EM screening and Newton polishing.
#include "ident/regression/batch_regression.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <numeric>
#include <random>
#include <utility>

#include <Eigen/Core>

#include "common/dense_decompositions.h"
#include "common/error.h"
#include "ident/regression/internal/batch_regression_common.h"

namespace ident::batch_regression_detail {
namespace {

struct CauchyPoint {
  Eigen::VectorXd beta;
  double gamma = 0;
  double nll = kInf;  // with n log π
  int iterations = 0;
  double gradient_norm = kInf;
};

// Σ log(1 + u_i²) without overflow: 2 log|u| where u² would (the two agree to 1e-300 there). Vectorised
// unless some |u| is that large.
template <class Derived>
double SumLogOnePlusSquare(const Eigen::ArrayBase<Derived>& u) {
  if (u.abs().maxCoeff() < 1e150) return (1 + u.square()).log().sum();
  return u.unaryExpr([](double v) { return std::abs(v) < 1e150 ? std::log1p(v * v) : 2 * std::log(std::abs(v)); })
      .sum();
}

class CauchyProblem {
 public:
  CauchyProblem(const Eigen::MatrixXd& Q, const Eigen::Ref<const Eigen::VectorXd>& y)
      : Q_(Q),
        y_(y),
        r_(Q.rows()),
        w_(Q.rows()),
        t_(Q.rows()),
        Qb_(Q.rows()),
        u_(Q.rows()),
        w1_(Q.rows()),
        uw_(Q.rows()),
        Qw_(Q.rows(), Q.cols()) {}

  Eigen::Index n() const { return Q_.rows(); }
  Eigen::Index p() const { return Q_.cols(); }
  const Eigen::MatrixXd& Q() const { return Q_; }
  const Eigen::VectorXd& y() const { return y_; }

  double Nll(const Eigen::VectorXd& beta, double gamma) const {
    if (!(gamma > 0) || !std::isfinite(gamma)) return kInf;
    // Σ log(r² + γ²) − n log γ in the standardised residuals r/γ: no overflow of r² for a gross error.
    r_.noalias() = y_ - Q_ * beta;
    const double nd = static_cast<double>(n());
    u_ = r_.array() * (1 / gamma);
    return SumLogOnePlusSquare(u_) + nd * std::log(gamma) + nd * std::log(std::numbers::pi);
  }

  // A start at β with γ = median|r| (mean |r| if that is 0); nll = +inf if the residuals all vanish.
  CauchyPoint Start(Eigen::VectorXd beta) const {
    r_.noalias() = y_ - Q_ * beta;
    double gamma = MedianAbs(r_, sorted_);
    if (!(gamma > 0)) gamma = r_.cwiseAbs().mean();
    CauchyPoint point{std::move(beta), gamma};
    point.nll = Nll(point.beta, point.gamma);
    return point;
  }

  // One ECM step of the t (k = 1) model: weights at the current point, then β, then γ (never increases
  // the NLL). Returns false (point unchanged) if the weighted fit or γ breaks down.
  bool EmStep(CauchyPoint& point) const {
    // w = 2γ²/(r² + γ²), and γ'² = mean(w r'²), as mean((√w r')²) where r'² overflows: a gross error's
    // weight underflows to 0, never 0·∞.
    r_.noalias() = y_ - Q_ * point.beta;
    w_ = 2 / (1 + (r_.array() * (1 / point.gamma)).square());
    Eigen::VectorXd beta;
    if (!WeightedFit(Q_, y_, w_, beta, Qw_)) return false;
    Qb_.noalias() = Q_ * beta;
    double weighted = (w_.array() * (y_ - Qb_).array().square()).sum();
    if (!std::isfinite(weighted)) weighted = (w_.array().sqrt() * (y_ - Qb_).array()).square().sum();
    const double gamma = std::sqrt(weighted / static_cast<double>(n()));
    if (!(gamma > 0) || !std::isfinite(gamma)) return false;
    point.beta = std::move(beta);
    point.gamma = gamma;
    ++point.iterations;
    return true;
  }

  // Gradient g and Hessian H of the NLL in (β, η = log γ) at `point`.
  void Derivatives(const CauchyPoint& point, Eigen::VectorXd& g, Eigen::MatrixXd& H) const {
    // In the standardised residuals u = r/γ, through w = 1/(1 + u²) and uw = u·w only (u²w² = (uw)²): the
    // same sums as in r and γ², without the under/overflow of (r² + γ²)² on data in very small or large
    // units, or of u² for a gross error (whose w and uw then underflow to 0).
    const Eigen::Index np = p();
    const double inv_gamma = 1 / point.gamma;
    Qb_.noalias() = Q_ * point.beta;
    u_ = (y_ - Qb_).array() * inv_gamma;
    w1_ = 1 / (1 + u_.square());
    uw_ = u_ * w1_;
    g.resize(np + 1);
    H.resize(np + 1, np + 1);
    t_ = 2 * uw_;
    g.head(np) = -inv_gamma * (Q_.transpose() * t_.matrix());
    g(np) = 2 * w1_.sum() - static_cast<double>(n());
    t_ = 2 * (w1_.square() - uw_.square());  // 2(1 − u²)/(1 + u²)²
    Qw_ = Q_.array().colwise() * t_;
    H.topLeftCorner(np, np) = (inv_gamma * inv_gamma) * (Qw_.transpose() * Q_);
    t_ = 4 * uw_ * w1_;  // 4u/(1 + u²)²
    H.col(np).head(np) = inv_gamma * (Q_.transpose() * t_.matrix());
    H.row(np).head(np) = H.col(np).head(np).transpose();
    H(np, np) = 4 * uw_.square().sum();  // Σ 4u²/(1 + u²)²
  }

  // ‖(γ ∂/∂β, ∂/∂η)‖: scale free (each term of the sums is O(1)).
  static double ScaledGradientNorm(const Eigen::VectorXd& g, double gamma) {
    const Eigen::Index np = g.size() - 1;
    return std::hypot(gamma * g.head(np).norm(), g(np));
  }

  // Newton on (β, η) with Armijo backtracking; false (point unchanged) if H is not positive definite or no
  // step length decreases the NLL. Where the predicted decrease is below the NLL's round-off, the full step
  // is judged by the scaled gradient instead (it must shrink below point.gradient_norm).
  bool NewtonStep(CauchyPoint& point, const Eigen::VectorXd& g, const Eigen::MatrixXd& H) const {
    const Eigen::LLT<Eigen::MatrixXd> llt = dense::Llt(H);
    if (llt.info() != Eigen::Success) return false;
    const Eigen::VectorXd step = -llt.solve(g);
    const Eigen::Index np = p();
    const double slope = g.dot(step);
    if (!(slope < 0)) return false;
    if (-slope <= 1e-13 * (std::abs(point.nll) + static_cast<double>(n()))) {
      CauchyPoint trial{point.beta + step.head(np), point.gamma * std::exp(step(np))};
      Eigen::VectorXd g_trial;
      Eigen::MatrixXd H_trial;
      Derivatives(trial, g_trial, H_trial);
      if (!(ScaledGradientNorm(g_trial, trial.gamma) < point.gradient_norm)) return false;
      point.beta = std::move(trial.beta);
      point.gamma = trial.gamma;
      point.nll = Nll(point.beta, point.gamma);
      ++point.iterations;
      return true;
    }
    for (double t = 1; t > 1e-10; t /= 2) {
      Eigen::VectorXd beta = point.beta + t * step.head(np);
      const double gamma = point.gamma * std::exp(t * step(np));
      const double nll = Nll(beta, gamma);
      if (nll <= point.nll + 1e-4 * t * slope) {
        point.beta = std::move(beta);
        point.gamma = gamma;
        point.nll = nll;
        ++point.iterations;
        return true;
      }
    }
    return false;
  }

  // Newton (EM where Newton fails) until the scaled gradient is below `tolerance`, no step makes progress,
  // or `max_iterations` steps.
  void Polish(CauchyPoint& point, double tolerance, int max_iterations) const {
    Eigen::VectorXd g;
    Eigen::MatrixXd H;
    for (int step = 0;; ++step) {
      Derivatives(point, g, H);
      point.gradient_norm = ScaledGradientNorm(g, point.gamma);
      if (point.gradient_norm <= tolerance || step >= max_iterations) return;
      if (NewtonStep(point, g, H)) continue;
      const double before = point.nll;
      if (!EmStep(point)) return;
      point.nll = Nll(point.beta, point.gamma);
      if (!(point.nll < before)) return;  // neither method makes progress: round-off level
    }
  }

  // Cov(β): the sandwich A⁻¹BA⁻¹, or the β block of the inverse Hessian in (β, η) if A is not positive
  // definite; NaN if neither is invertible.
  Eigen::MatrixXd Covariance(const CauchyPoint& point) const {
    const Eigen::Index np = p();
    Eigen::VectorXd g;
    Eigen::MatrixXd H;
    Derivatives(point, g, H);
    const Eigen::MatrixXd A = H.topLeftCorner(np, np);
    const Eigen::LLT<Eigen::MatrixXd> llt = dense::Llt(A);
    if (llt.info() == Eigen::Success) {
      const Eigen::ArrayXd u = (y_ - Q_ * point.beta).array() / point.gamma;  // ψ(r) = 2r/(r² + γ²)
      const Eigen::MatrixXd Qpsi = Q_.array().colwise() * (2 * (u / (1 + u.square())) / point.gamma);
      const Eigen::MatrixXd Ainv = dense::Inverse(llt);
      return Ainv * (Qpsi.transpose() * Qpsi) * Ainv;
    }
    const Eigen::FullPivLU<Eigen::MatrixXd> lu = dense::FullPivLu(H);
    if (!lu.isInvertible()) return Eigen::MatrixXd::Constant(np, np, kNaN);
    return dense::Inverse(lu).topLeftCorner(np, np);
  }

 private:
  const Eigen::MatrixXd& Q_;
  const Eigen::VectorXd y_;
  // Workspace of the O(n) steps, sized once: a fit runs hundreds of them, and fresh n-row temporaries each
  // time cost page faults where the allocator hands large blocks back to the system at once (as Dask
  // workers make it do, with MALLOC_TRIM_THRESHOLD_).
  mutable Eigen::VectorXd r_, w_;
  mutable Eigen::ArrayXd t_;
  mutable Eigen::VectorXd Qb_;
  mutable Eigen::ArrayXd u_, w1_, uw_;
  mutable Eigen::MatrixXd Qw_;
  mutable std::vector<double> sorted_;
};

// Draws elemental subsets (ρ distinct rows, solved exactly); a partial Fisher–Yates shuffle of a kept
// permutation, so a draw costs O(ρ).
class ElementalSampler {
 public:
  ElementalSampler(const CauchyProblem& problem, std::uint64_t seed)
      : problem_(problem), rng_(seed), order_(static_cast<std::size_t>(problem.n())) {
    std::iota(order_.begin(), order_.end(), Eigen::Index{0});
  }

  // β fitting a fresh random subset exactly; false if the subset's rows are singular.
  bool Draw(Eigen::VectorXd& beta) {
    const Eigen::Index p = problem_.p();
    const std::size_t n = order_.size();
    Eigen::MatrixXd Qs(p, p);
    Eigen::VectorXd ys(p);
    for (Eigen::Index j = 0; j < p; ++j) {
      const std::size_t jj = static_cast<std::size_t>(j);
      std::swap(order_[jj], order_[jj + UniformIndex(rng_, n - jj)]);
      Qs.row(j) = problem_.Q().row(order_[jj]);
      ys(j) = problem_.y()(order_[jj]);
    }
    const Eigen::FullPivLU<Eigen::MatrixXd> lu = dense::FullPivLu(Qs);
    if (!lu.isInvertible()) return false;
    beta = lu.solve(ys);
    return beta.allFinite();
  }

 private:
  const CauchyProblem& problem_;
  std::mt19937_64 rng_;
  std::vector<Eigen::Index> order_;
};

// Concentration steps from β: least squares on the h rows with the smallest squared residuals, until the
// sum of those h squares stops decreasing (at most 50 steps).
// The n-row vectors and the n×p matrix of the steps are sized once, for all steps.
Eigen::VectorXd Concentrate(const CauchyProblem& problem, Eigen::VectorXd beta) {
  const Eigen::Index n = problem.n(), p = problem.p();
  const Eigen::Index h = (n + p + 1) / 2;
  std::vector<Eigen::Index> idx(static_cast<std::size_t>(n));
  Eigen::VectorXd Qb(n), r2(n), w(n);
  Eigen::MatrixXd Qw(n, p);
  double best = kInf;
  for (int step = 0; step < 50; ++step) {
    Qb.noalias() = problem.Q() * beta;
    r2 = (problem.y() - Qb).cwiseAbs2();
    std::iota(idx.begin(), idx.end(), Eigen::Index{0});
    std::nth_element(idx.begin(), idx.begin() + h - 1, idx.end(),
                     [&](Eigen::Index a, Eigen::Index b) { return r2(a) < r2(b); });
    double sum = 0;
    for (Eigen::Index i = 0; i < h; ++i) sum += r2(idx[static_cast<std::size_t>(i)]);
    if (!(sum < best)) break;
    best = sum;
    w.setZero();
    for (Eigen::Index i = 0; i < h; ++i) w(idx[static_cast<std::size_t>(i)]) = 1;
    Eigen::VectorXd next;
    if (!WeightedFit(problem.Q(), problem.y(), w, next, Qw)) break;
    beta = std::move(next);
  }
  return beta;
}

// The starts of CauchyMlRegression, each after `screening_iterations` EM steps, NLL evaluated.
std::vector<CauchyPoint> ScreenedStarts(const CauchyProblem& problem, const CauchyMlOptions& options) {
  const int p = static_cast<int>(problem.p());
  const int elemental =
      options.elemental_starts == CauchyMlOptions::kAuto ? std::max(50, 20 * p) : options.elemental_starts;
  std::vector<Eigen::VectorXd> betas;
  if (options.ls_start) betas.push_back(problem.Q().transpose() * problem.y());
  ElementalSampler sampler(problem, options.seed);
  Eigen::VectorXd beta;
  // Elemental subsets first, then the LTS starts from further subsets; a singular subset is redrawn (at most
  // ten draws per start).
  for (int k = 0, drawn = 0; k < elemental + options.lts_starts && drawn < 10 * (elemental + options.lts_starts);
       ++drawn) {
    if (!sampler.Draw(beta)) continue;
    betas.push_back(k < elemental ? beta : Concentrate(problem, beta));
    ++k;
  }
  std::vector<CauchyPoint> points;
  points.reserve(betas.size());
  for (Eigen::VectorXd& b : betas) {
    CauchyPoint point = problem.Start(std::move(b));
    if (!std::isfinite(point.nll)) continue;
    for (int i = 0; i < options.screening_iterations && problem.EmStep(point); ++i) {}
    point.nll = problem.Nll(point.beta, point.gamma);
    if (std::isfinite(point.nll)) points.push_back(std::move(point));
  }
  return points;
}

}  // namespace
}  // namespace ident::batch_regression_detail

namespace ident {

std::string CauchyMlOptions::Validate() const {
  if (elemental_starts < 0 && elemental_starts != kAuto)
    return fmt::format("cauchy elemental_starts = {}; need >= 0 or kAuto", elemental_starts);
  if (lts_starts < 0) return fmt::format("cauchy lts_starts = {}; need >= 0", lts_starts);
  if (elemental_starts == 0 && lts_starts == 0 && !ls_start)
    return "cauchy: no starts (elemental_starts = lts_starts = 0, ls_start = false); need at least one";
  if (screening_iterations < 0) return fmt::format("cauchy screening_iterations = {}; need >= 0", screening_iterations);
  if (polished < 1) return fmt::format("cauchy polished = {}; need >= 1", polished);
  if (!(gradient_tolerance >= 0)) return fmt::format("cauchy gradient_tolerance = {}; need >= 0", gradient_tolerance);
  if (max_iterations < 0) return fmt::format("cauchy max_iterations = {}; need >= 0", max_iterations);
  return "";
}

BatchRegressionResult CauchyMlRegression(const Eigen::Ref<const Eigen::MatrixXd>& Z,
                                         const Eigen::Ref<const Eigen::VectorXd>& y, const CauchyMlOptions& options) {
  using namespace batch_regression_detail;
  const std::string error = options.Validate();
  IDENT_REQUIRE(error.empty(), "{}", error);
  RequireRegressionData(Z, y);
  const Orthonormalised f = RequireFullRank(Z);
  // y in units of a power of two near its median magnitude (its largest if that is 0, and no smaller than
  // 2^-1000 of the largest, so that y stays finite in them). Every step below is then the same, bit for
  // bit, for y and 2^k·y: the NLL's n·log γ term, and with it the stopping and line-search tests that
  // compare NLL changes with |NLL|, would otherwise depend on the units of y.
  Eigen::VectorXd magnitude = y.cwiseAbs();
  const double largest = magnitude.maxCoeff();
  const Eigen::Index middle = magnitude.size() / 2;
  std::nth_element(magnitude.data(), magnitude.data() + middle, magnitude.data() + magnitude.size());
  const int exponent = largest > 0 ? std::max(std::ilogb(magnitude(middle) > 0 ? magnitude(middle) : largest),
                                              std::ilogb(largest) - 1000)
                                   : 0;
  const Eigen::VectorXd y_scaled = y.unaryExpr([exponent](double v) { return std::ldexp(v, -exponent); });
  const CauchyProblem problem(f.Q, y_scaled);

  std::vector<CauchyPoint> points = ScreenedStarts(problem, options);
  BatchRegressionResult result;
  result.starts = static_cast<int>(points.size());
  std::sort(points.begin(), points.end(), [](const CauchyPoint& a, const CauchyPoint& b) { return a.nll < b.nll; });
  // The best `polished` distinct screened points (another within 1% of γ in every coordinate of β and in γ
  // is taken to be on its way to the same optimum).
  std::vector<CauchyPoint> chosen;
  for (const CauchyPoint& point : points) {
    if (static_cast<int>(chosen.size()) >= options.polished) break;
    const bool seen = std::any_of(chosen.begin(), chosen.end(), [&](const CauchyPoint& c) {
      return (point.beta - c.beta).cwiseAbs().maxCoeff() <= 1e-2 * c.gamma &&
             std::abs(std::log(point.gamma / c.gamma)) <= 1e-2;
    });
    if (!seen) chosen.push_back(point);
  }
  CauchyPoint best;
  for (CauchyPoint& point : chosen) {
    problem.Polish(point, options.gradient_tolerance, options.max_iterations);
    if (point.nll < best.nll) best = point;
  }
  if (!std::isfinite(best.nll)) {  // every start fits all samples exactly: γ → 0, the NLL → −∞
    result.theta = f.T * (f.Q.transpose() * y);
    result.covariance = Eigen::MatrixXd::Zero(Z.cols(), Z.cols());
    result.objective = -kInf;
    return result;
  }
  const auto in_units_of_y = [](int power) { return [power](double v) { return std::ldexp(v, power); }; };
  result.theta = (f.T * best.beta).unaryExpr(in_units_of_y(exponent));
  result.scale = std::ldexp(best.gamma, exponent);
  result.covariance = (f.T * problem.Covariance(best) * f.T.transpose()).unaryExpr(in_units_of_y(2 * exponent));
  result.objective = best.nll + static_cast<double>(y.size()) * exponent * std::numbers::ln2;
  result.iterations = best.iterations;
  result.gradient_norm = best.gradient_norm;
  result.converged = best.gradient_norm <= options.gradient_tolerance;
  return result;
}

double CauchyNegativeLogLikelihood(const Eigen::Ref<const Eigen::MatrixXd>& Z,
                                   const Eigen::Ref<const Eigen::VectorXd>& y,
                                   const Eigen::Ref<const Eigen::VectorXd>& theta, double gamma) {
  IDENT_REQUIRE(Z.rows() == y.size() && Z.cols() == theta.size(), "Z is {}x{}, y has {} and theta {} entries", Z.rows(),
                Z.cols(), y.size(), theta.size());
  const double nd = static_cast<double>(y.size());
  const Eigen::ArrayXd u = (y - Z * theta).array() / gamma;
  return batch_regression_detail::SumLogOnePlusSquare(u) + nd * std::log(gamma) + nd * std::log(std::numbers::pi);
}

}  // namespace ident
