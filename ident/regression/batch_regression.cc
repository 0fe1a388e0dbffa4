#include "ident/regression/batch_regression.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <numeric>
#include <random>
#include <utility>

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <Eigen/QR>

#include "common/error.h"

// Helpers in a named namespace: the library builds as a unity build, where anonymous namespaces of other
// files share this translation unit.
namespace ident::batch_regression_detail {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Throws InvalidArgument naming the first problem with the regression data.
void RequireRegressionData(const Eigen::Ref<const Eigen::MatrixXd>& Z, const Eigen::Ref<const Eigen::VectorXd>& y) {
  IDENT_REQUIRE(Z.cols() >= 1, "Z has no columns; need at least one regressor");
  IDENT_REQUIRE(Z.rows() == y.size(), "Z has {} rows but y has {} entries; need one row per sample", Z.rows(),
                y.size());
  IDENT_REQUIRE(Z.rows() > Z.cols(), "n = {} samples for rho = {} regressors; need n > rho", Z.rows(), Z.cols());
  IDENT_REQUIRE(Z.allFinite(), "Z has a non-finite entry");
  IDENT_REQUIRE(y.allFinite(), "y has a non-finite entry");
}

// Z P = Q R (column-pivoted Householder QR), with the thin Q and T = P R⁻¹, so that β = T⁻¹Θ are the
// coefficients on the orthonormal columns of Q: ZΘ = Qβ, Θ = Tβ, Cov(Θ) = T Cov(β) T'.
struct Orthonormalised {
  Eigen::MatrixXd Q;
  Eigen::MatrixXd T;
  Eigen::Index rank = 0;
};

Orthonormalised Orthonormalise(const Eigen::Ref<const Eigen::MatrixXd>& Z) {
  const Eigen::Index n = Z.rows(), p = Z.cols();
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(Z);
  Orthonormalised f;
  f.rank = qr.rank();
  if (f.rank < p) return f;
  f.Q = qr.householderQ() * Eigen::MatrixXd::Identity(n, p);
  const Eigen::MatrixXd Rinv =
      qr.matrixR().topLeftCorner(p, p).triangularView<Eigen::Upper>().solve(Eigen::MatrixXd::Identity(p, p));
  f.T = qr.colsPermutation() * Rinv;
  return f;
}

Orthonormalised RequireFullRank(const Eigen::Ref<const Eigen::MatrixXd>& Z) {
  Orthonormalised f = Orthonormalise(Z);
  IDENT_REQUIRE(f.rank == Z.cols(), "Z has column rank {} < rho = {}; need full column rank", f.rank, Z.cols());
  return f;
}

// argmin_β Σ w_i (y_i − β'q_i)² by the normal equations on the orthonormal Q (well conditioned unless the
// weights are); nullopt-like: returns false if Q'WQ is not positive definite.
bool WeightedFit(const Eigen::MatrixXd& Q, const Eigen::VectorXd& y, const Eigen::VectorXd& w, Eigen::VectorXd& beta) {
  const Eigen::MatrixXd Qw = Q.array().colwise() * w.array();
  const Eigen::LLT<Eigen::MatrixXd> llt(Qw.transpose() * Q);
  if (llt.info() != Eigen::Success) return false;
  beta = llt.solve(Qw.transpose() * y);
  return beta.allFinite();
}

// Median of |v| (the mean of the two middle values for even n, as R's median).
double MedianAbs(const Eigen::VectorXd& v) {
  std::vector<double> a(v.data(), v.data() + v.size());
  for (double& x : a) x = std::abs(x);
  const std::size_t mid = a.size() / 2;
  std::nth_element(a.begin(), a.begin() + static_cast<std::ptrdiff_t>(mid), a.end());
  const double upper = a[mid];
  if (a.size() % 2 == 1) return upper;
  return 0.5 * (upper + *std::max_element(a.begin(), a.begin() + static_cast<std::ptrdiff_t>(mid)));
}

// A uniform index in [0, bound) from the generator's raw output (rejection sampling): unlike the std
// distributions, the same sequence on every standard library.
std::size_t UniformIndex(std::mt19937_64& rng, std::size_t bound) {
  const std::uint64_t b = bound;
  const std::uint64_t limit = std::numeric_limits<std::uint64_t>::max() / b * b;
  std::uint64_t x = rng();
  while (x >= limit) x = rng();
  return static_cast<std::size_t>(x % b);
}

// ---- Cauchy maximum likelihood on (β, η = log γ) -------------------------------------------------------

struct CauchyPoint {
  Eigen::VectorXd beta;
  double gamma = 0;
  double nll = kInf;  // with n log π
  int iterations = 0;
  double gradient_norm = kInf;
};

class CauchyProblem {
 public:
  CauchyProblem(const Eigen::MatrixXd& Q, const Eigen::Ref<const Eigen::VectorXd>& y) : Q_(Q), y_(y) {}

  Eigen::Index n() const { return Q_.rows(); }
  Eigen::Index p() const { return Q_.cols(); }
  const Eigen::MatrixXd& Q() const { return Q_; }
  const Eigen::VectorXd& y() const { return y_; }

  double Nll(const Eigen::VectorXd& beta, double gamma) const {
    if (!(gamma > 0) || !std::isfinite(gamma)) return kInf;
    const Eigen::VectorXd r = y_ - Q_ * beta;
    const double nd = static_cast<double>(n());
    const double g2 = gamma * gamma;
    return (r.array().square() + g2).log().sum() - nd * std::log(gamma) + nd * std::log(std::numbers::pi);
  }

  // A start at β with γ = median|r| (mean |r| if that is 0); nll = +inf if the residuals all vanish.
  CauchyPoint Start(Eigen::VectorXd beta) const {
    const Eigen::VectorXd r = y_ - Q_ * beta;
    double gamma = MedianAbs(r);
    if (!(gamma > 0)) gamma = r.cwiseAbs().mean();
    CauchyPoint point{std::move(beta), gamma};
    point.nll = Nll(point.beta, point.gamma);
    return point;
  }

  // One ECM step of the t (k = 1) model: weights at the current point, then β, then γ (never increases
  // the NLL). Returns false (point unchanged) if the weighted fit or γ breaks down.
  bool EmStep(CauchyPoint& point) const {
    const double g2 = point.gamma * point.gamma;
    const Eigen::VectorXd r = y_ - Q_ * point.beta;
    const Eigen::VectorXd w = 2 * g2 / (r.array().square() + g2);
    Eigen::VectorXd beta;
    if (!WeightedFit(Q_, y_, w, beta)) return false;
    const double gamma = std::sqrt(w.dot((y_ - Q_ * beta).cwiseAbs2()) / static_cast<double>(n()));
    if (!(gamma > 0) || !std::isfinite(gamma)) return false;
    point.beta = std::move(beta);
    point.gamma = gamma;
    ++point.iterations;
    return true;
  }

  // Gradient g and Hessian H of the NLL in (β, η = log γ) at `point`.
  void Derivatives(const CauchyPoint& point, Eigen::VectorXd& g, Eigen::MatrixXd& H) const {
    // In the standardised residuals u = r/γ (d = 1 + u²): the same sums as in r and γ², without the
    // under/overflow of (r² + γ²)² on data in very small or large units.
    const Eigen::Index np = p();
    const double inv_gamma = 1 / point.gamma;
    const Eigen::ArrayXd u = (y_ - Q_ * point.beta).array() * inv_gamma;
    const Eigen::ArrayXd d = 1 + u.square();
    const Eigen::ArrayXd d2 = d.square();
    g.resize(np + 1);
    H.resize(np + 1, np + 1);
    g.head(np) = -inv_gamma * (Q_.transpose() * (2 * u / d).matrix());
    g(np) = (2 / d).sum() - static_cast<double>(n());
    const Eigen::MatrixXd Qa = Q_.array().colwise() * (2 * (1 - u.square()) / d2);
    H.topLeftCorner(np, np) = (inv_gamma * inv_gamma) * (Qa.transpose() * Q_);
    H.col(np).head(np) = inv_gamma * (Q_.transpose() * (4 * u / d2).matrix());
    H.row(np).head(np) = H.col(np).head(np).transpose();
    H(np, np) = (4 * u.square() / d2).sum();
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
    const Eigen::LLT<Eigen::MatrixXd> llt(H);
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
    const Eigen::LLT<Eigen::MatrixXd> llt(A);
    if (llt.info() == Eigen::Success) {
      const Eigen::ArrayXd u = (y_ - Q_ * point.beta).array() / point.gamma;  // ψ(r) = 2r/(r² + γ²)
      const Eigen::MatrixXd Qpsi = Q_.array().colwise() * (2 * u / (1 + u.square()) / point.gamma);
      const Eigen::MatrixXd Ainv = llt.solve(Eigen::MatrixXd::Identity(np, np));
      return Ainv * (Qpsi.transpose() * Qpsi) * Ainv;
    }
    const Eigen::FullPivLU<Eigen::MatrixXd> lu(H);
    if (!lu.isInvertible()) return Eigen::MatrixXd::Constant(np, np, kNaN);
    return lu.inverse().topLeftCorner(np, np);
  }

 private:
  const Eigen::MatrixXd& Q_;
  const Eigen::VectorXd y_;
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
    const Eigen::FullPivLU<Eigen::MatrixXd> lu(Qs);
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
Eigen::VectorXd Concentrate(const CauchyProblem& problem, Eigen::VectorXd beta) {
  const Eigen::Index n = problem.n(), p = problem.p();
  const Eigen::Index h = (n + p + 1) / 2;
  std::vector<Eigen::Index> idx(static_cast<std::size_t>(n));
  double best = kInf;
  for (int step = 0; step < 50; ++step) {
    const Eigen::VectorXd r2 = (problem.y() - problem.Q() * beta).cwiseAbs2();
    std::iota(idx.begin(), idx.end(), Eigen::Index{0});
    std::nth_element(idx.begin(), idx.begin() + h - 1, idx.end(),
                     [&](Eigen::Index a, Eigen::Index b) { return r2(a) < r2(b); });
    double sum = 0;
    for (Eigen::Index i = 0; i < h; ++i) sum += r2(idx[static_cast<std::size_t>(i)]);
    if (!(sum < best)) break;
    best = sum;
    Eigen::VectorXd w = Eigen::VectorXd::Zero(n);
    for (Eigen::Index i = 0; i < h; ++i) w(idx[static_cast<std::size_t>(i)]) = 1;
    Eigen::VectorXd next;
    if (!WeightedFit(problem.Q(), problem.y(), w, next)) break;
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

std::string HuberOptions::Validate() const {
  if (!(k > 0) || !std::isfinite(k)) return fmt::format("huber k = {}; need a finite k > 0", k);
  if (!(tolerance >= 0)) return fmt::format("huber tolerance = {}; need tolerance >= 0", tolerance);
  if (max_iterations < 1) return fmt::format("huber max_iterations = {}; need >= 1", max_iterations);
  return "";
}

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

BatchRegressionResult HuberRegression(const Eigen::Ref<const Eigen::MatrixXd>& Z,
                                      const Eigen::Ref<const Eigen::VectorXd>& y, const HuberOptions& options) {
  using namespace batch_regression_detail;
  const std::string error = options.Validate();
  IDENT_REQUIRE(error.empty(), "{}", error);
  RequireRegressionData(Z, y);
  const Orthonormalised f = RequireFullRank(Z);
  const Eigen::Index n = Z.rows(), p = Z.cols();
  const double k = options.k;

  BatchRegressionResult result;
  result.starts = 1;
  Eigen::VectorXd beta = f.Q.transpose() * y;  // least squares
  Eigen::VectorXd r = y - f.Q * beta;
  double s = 0;
  while (result.iterations < options.max_iterations) {
    s = MedianAbs(r) / 0.6745;
    if (!(s > 0)) {  // more than half the residuals vanish: an exact fit (rlm stops here too)
      result.converged = true;
      break;
    }
    const Eigen::VectorXd w = (k * s / r.array().abs()).min(1.0);
    if (!WeightedFit(f.Q, y, w, beta)) break;
    Eigen::VectorXd next = y - f.Q * beta;
    ++result.iterations;
    // rlm's relative change of the residuals, without its absolute floor max(1e-20, ‖r‖²), which stops the
    // iteration at once on data in small units (‖r‖² > 0 here: the MAD scale s is positive).
    const double delta = std::sqrt((next - r).squaredNorm() / r.squaredNorm());
    r = std::move(next);
    if (delta <= options.tolerance) {
      result.converged = true;
      break;
    }
  }
  result.theta = f.T * beta;
  result.scale = s;
  const Eigen::MatrixXd unscaled = f.T * f.T.transpose();  // (Z'Z)⁻¹
  if (!(s > 0)) {
    result.covariance = Eigen::MatrixXd::Zero(p, p);
    return result;
  }
  const Eigen::ArrayXd u = r.array() / s;
  const Eigen::ArrayXd psi = u.max(-k).min(k);
  const Eigen::ArrayXd dpsi = (u.abs() <= k).cast<double>();
  const double nd = static_cast<double>(n);
  const double mean = dpsi.mean();
  const double var = (dpsi - mean).square().sum() / (nd - 1);
  const double kappa = 1 + static_cast<double>(p) * var / (nd * mean * mean);
  const double S = s * s * psi.square().sum() / static_cast<double>(n - p);
  result.covariance = (kappa * kappa / (mean * mean) * S) * unscaled;
  result.objective = (u.abs() <= k).select(0.5 * u.square(), k * u.abs() - 0.5 * k * k).sum();
  return result;
}

BatchRegressionResult CauchyMlRegression(const Eigen::Ref<const Eigen::MatrixXd>& Z,
                                         const Eigen::Ref<const Eigen::VectorXd>& y, const CauchyMlOptions& options) {
  using namespace batch_regression_detail;
  const std::string error = options.Validate();
  IDENT_REQUIRE(error.empty(), "{}", error);
  RequireRegressionData(Z, y);
  const Orthonormalised f = RequireFullRank(Z);
  const CauchyProblem problem(f.Q, y);

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
  result.theta = f.T * best.beta;
  result.scale = best.gamma;
  result.covariance = f.T * problem.Covariance(best) * f.T.transpose();
  result.objective = best.nll;
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
  return ((y - Z * theta).array().square() + gamma * gamma).log().sum() - nd * std::log(gamma) +
         nd * std::log(std::numbers::pi);
}

// ---- BatchRegressionEstimator ----------------------------------------------------------------------------

namespace batch_regression_detail {
namespace {
BatchRegressionResult Unsolved(int p) {
  BatchRegressionResult r;
  r.theta = Eigen::VectorXd::Zero(p);
  r.scale = kNaN;
  r.covariance = Eigen::MatrixXd::Constant(p, p, kInf);
  r.objective = kNaN;
  return r;
}

const BatchRegressionOptions& CheckedOptions(int num_parameters, const BatchRegressionOptions& options) {
  IDENT_REQUIRE(num_parameters >= 1, "num_parameters = {}; need >= 1", num_parameters);
  const std::string error =
      options.method == BatchMethod::kHuber ? options.huber.Validate() : options.cauchy.Validate();
  IDENT_REQUIRE(error.empty(), "{}", error);
  return options;
}
}  // namespace
}  // namespace batch_regression_detail

BatchRegressionEstimator::BatchRegressionEstimator(int num_parameters, const BatchRegressionOptions& options)
    : num_parameters_(num_parameters),
      options_(batch_regression_detail::CheckedOptions(num_parameters, options)),
      cache_(batch_regression_detail::Unsolved(num_parameters)) {}

void BatchRegressionEstimator::Reset() {
  y_.clear();
  z_.clear();
  cache_ = batch_regression_detail::Unsolved(num_parameters_);
  solved_ = true;
}

const BatchRegressionResult& BatchRegressionEstimator::Solved() const {
  if (solved_) return cache_;
  solved_ = true;
  const Eigen::Index n = static_cast<Eigen::Index>(y_.size()), p = num_parameters_;
  const Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> Zrows(z_.data(), n, p);
  const Eigen::MatrixXd Z = Zrows;
  const Eigen::Map<const Eigen::VectorXd> y(y_.data(), n);
  if (n <= p || batch_regression_detail::Orthonormalise(Z).rank < p) {
    cache_ = batch_regression_detail::Unsolved(num_parameters_);
  } else if (options_.method == BatchMethod::kHuber) {
    cache_ = HuberRegression(Z, y, options_.huber);
  } else {
    cache_ = CauchyMlRegression(Z, y, options_.cauchy);
  }
  return cache_;
}

}  // namespace ident
