#include "models/penalties.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "common/dense_decompositions.h"
#include "common/error.h"

namespace ident::models {
namespace {

void RequireDim(int dim) { IDENT_REQUIRE(dim >= 1, "penalty dimension = {}; need >= 1", dim); }

PlqForm Identity(int m, double lo, double hi, double M) {
  PlqForm f;
  f.B = Eigen::MatrixXd::Identity(m, m);
  f.b = Eigen::VectorXd::Zero(m);
  f.M = M * Eigen::MatrixXd::Identity(m, m);
  f.lo = Eigen::VectorXd::Constant(m, lo);
  f.hi = Eigen::VectorXd::Constant(m, hi);
  f.p = Eigen::VectorXd::Zero(m);
  return f;
}

// 1/2 v'A v without a temporary (A symmetric).
double HalfQuadraticForm(const Eigen::MatrixXd& A, const Eigen::Ref<const Eigen::VectorXd>& v) {
  double sum = 0;
  for (Eigen::Index j = 0; j < A.cols(); ++j) {
    double s = 0;
    for (Eigen::Index i = 0; i < A.rows(); ++i) s += A(i, j) * v(i);
    sum += s * v(j);
  }
  return 0.5 * sum;
}

bool IsDiagonal(const Eigen::MatrixXd& M) {
  for (int i = 0; i < M.rows(); ++i)
    for (int j = 0; j < M.cols(); ++j)
      if (i != j && M(i, j) != 0.0) return false;
  return true;
}

}  // namespace

Penalty Penalty::Quadratic(const Eigen::MatrixXd& covariance) {
  const int m = static_cast<int>(covariance.rows());
  IDENT_REQUIRE(m >= 1 && covariance.cols() == m, "covariance is {}x{}; need a non-empty square matrix",
                covariance.rows(), covariance.cols());
  IDENT_REQUIRE(covariance.allFinite(), "covariance has a non-finite entry");
  const double scale = covariance.cwiseAbs().maxCoeff();
  IDENT_REQUIRE(((covariance - covariance.transpose()).cwiseAbs().array() <= 1e-12 * scale).all(),
                "covariance is not symmetric");
  const Eigen::LLT<Eigen::MatrixXd> llt = dense::Llt(covariance);
  IDENT_REQUIRE(llt.info() == Eigen::Success && scale > 0, "covariance is not positive definite");
  Penalty f(Kind::kQuadratic, m);
  f.matrix_ = covariance;
  f.precision_ = dense::Inverse(llt);
  f.plq_ = Identity(m, -kInfinity, kInfinity, 0.0);
  f.plq_.M = covariance;  // sup_u { u'r - 1/2 u'C u } = 1/2 r'C^-1 r
  f.plq_.diagonal_M = IsDiagonal(covariance);
  f.conj_lo_ = Eigen::VectorXd::Constant(m, -kInfinity);
  f.conj_hi_ = Eigen::VectorXd::Constant(m, kInfinity);
  return f;
}

Penalty Penalty::L1(int dim) {
  RequireDim(dim);
  Penalty f(Kind::kL1, dim);
  f.plq_ = Identity(dim, -1.0, 1.0, 0.0);  // |r| = sup_{|u| <= 1} u r
  f.conj_lo_ = f.plq_.lo;
  f.conj_hi_ = f.plq_.hi;
  return f;
}

Penalty Penalty::Huber(double kappa, int dim) {
  RequireDim(dim);
  IDENT_REQUIRE(std::isfinite(kappa) && kappa > 0, "huber kappa = {}; need kappa > 0", kappa);
  Penalty f(Kind::kHuber, dim);
  f.parameter_ = kappa;
  f.plq_ = Identity(dim, -kappa, kappa, 1.0);  // sup_{|u| <= kappa} { u r - u^2/2 }
  f.conj_lo_ = f.plq_.lo;
  f.conj_hi_ = f.plq_.hi;
  return f;
}

Penalty Penalty::Vapnik(double epsilon, int dim) {
  RequireDim(dim);
  IDENT_REQUIRE(std::isfinite(epsilon) && epsilon >= 0, "vapnik epsilon = {}; need epsilon >= 0", epsilon);
  Penalty f(Kind::kVapnik, dim);
  f.parameter_ = epsilon;
  // max(0, r - eps) + max(0, -r - eps) = sup_{u in [0,1]^2} { u1 (r - eps) + u2 (-r - eps) }  [ABP sec. 3]
  PlqForm& q = f.plq_;
  q.B.resize(2 * dim, dim);
  q.B << Eigen::MatrixXd::Identity(dim, dim), -Eigen::MatrixXd::Identity(dim, dim);
  q.b = Eigen::VectorXd::Constant(2 * dim, epsilon);
  q.M = Eigen::MatrixXd::Zero(2 * dim, 2 * dim);
  q.lo = Eigen::VectorXd::Zero(2 * dim);
  q.hi = Eigen::VectorXd::Ones(2 * dim);
  q.p = Eigen::VectorXd::Zero(dim);
  f.conj_lo_ = Eigen::VectorXd::Constant(dim, -1.0);
  f.conj_hi_ = Eigen::VectorXd::Constant(dim, 1.0);
  return f;
}

Penalty Penalty::Quantile(double tau, int dim) {
  RequireDim(dim);
  IDENT_REQUIRE(std::isfinite(tau) && tau > 0 && tau < 1, "quantile tau = {}; need 0 < tau < 1", tau);
  Penalty f(Kind::kQuantile, dim);
  f.parameter_ = tau;
  f.plq_ = Identity(dim, tau - 1.0, tau, 0.0);  // sup_{tau-1 <= u <= tau} u r
  f.conj_lo_ = f.plq_.lo;
  f.conj_hi_ = f.plq_.hi;
  return f;
}

Penalty Penalty::BoxMonitoring(const Eigen::VectorXd& lo, const Eigen::VectorXd& hi, const Eigen::MatrixXd& M) {
  const int m = static_cast<int>(lo.size());
  RequireDim(m);
  IDENT_REQUIRE(hi.size() == m, "box has {} lower and {} upper bounds", m, hi.size());
  IDENT_REQUIRE(M.rows() == m && M.cols() == m, "M is {}x{}; need {}x{}", M.rows(), M.cols(), m, m);
  IDENT_REQUIRE(M.allFinite(), "M has a non-finite entry");
  IDENT_REQUIRE(((M - M.transpose()).cwiseAbs().array() <= 1e-12 * (1 + M.cwiseAbs().maxCoeff())).all(),
                "M is not symmetric");
  bool unbounded = false;
  for (int i = 0; i < m; ++i) {
    IDENT_REQUIRE(!std::isnan(lo(i)) && !std::isnan(hi(i)) && lo(i) < hi(i) && lo(i) < kInfinity && hi(i) > -kInfinity,
                  "box bound {}: lo = {}, hi = {}; need lo < hi", i, lo(i), hi(i));
    unbounded = unbounded || std::isinf(lo(i)) || std::isinf(hi(i));
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig = dense::SymmetricEigen(M);
  const double min_eig = eig.eigenvalues().minCoeff();
  IDENT_REQUIRE(min_eig >= -1e-12 * (1 + M.cwiseAbs().maxCoeff()), "M is not positive semidefinite (eigenvalue {})",
                min_eig);
  IDENT_REQUIRE(!unbounded || min_eig > 0,
                "M must be positive definite when the box U is unbounded (else dom rho is not full-dimensional)");
  Penalty f(Kind::kBoxMonitoring, m);
  f.matrix_ = M;
  f.box_lo_ = lo;
  f.box_hi_ = hi;
  f.plq_ = Identity(m, 0, 0, 0);
  f.plq_.M = M;
  f.plq_.lo = lo;
  f.plq_.hi = hi;
  f.plq_.diagonal_M = IsDiagonal(M);
  f.conj_lo_ = lo;
  f.conj_hi_ = hi;
  return f;
}

Penalty Penalty::PiecewiseLinear(const Eigen::VectorXd& knots, const Eigen::VectorXd& values) {
  const int J = static_cast<int>(knots.size()) - 1;  // number of linear pieces
  IDENT_REQUIRE(J >= 1, "piecewise_linear needs at least 2 knots, got {}", knots.size());
  IDENT_REQUIRE(values.size() == knots.size(), "piecewise_linear has {} knots but {} values", knots.size(),
                values.size());
  IDENT_REQUIRE(knots.allFinite() && values.allFinite(), "piecewise_linear knots/values must be finite");
  Eigen::VectorXd slope(J);
  for (int j = 0; j < J; ++j) {
    IDENT_REQUIRE(knots(j + 1) > knots(j), "piecewise_linear knots must increase strictly (knot {} = {} <= {})", j + 1,
                  knots(j + 1), knots(j));
    slope(j) = (values(j + 1) - values(j)) / (knots(j + 1) - knots(j));
  }
  // Relative to the steepest slope, so that the same penalty in other units (knots × s, values × s²) keeps
  // the same kinks.
  const double tol = 1e-9 * slope.cwiseAbs().maxCoeff();
  for (int j = 1; j < J; ++j)
    IDENT_REQUIRE(slope(j) >= slope(j - 1) - tol, "piecewise_linear is not convex at knot {} (slope {} then {})", j,
                  slope(j - 1), slope(j));
  Penalty f(Kind::kPiecewiseLinear, 1);
  f.knots_ = knots;
  f.values_ = values;
  // rho(r) = v_0 + a_1 (r - k_0) + sum_j (a_j - a_{j-1}) (r - k_{j-1})^+ + indicator(k_0 <= r <= k_J), with
  //   (a_j - a_{j-1}) (r - k)^+ = sup_{0 <= u <= a_j - a_{j-1}} u (r - k),
  //   indicator(r <= k_J) = sup_{u >= 0} u (r - k_J),  indicator(r >= k_0) = sup_{u >= 0} u (k_0 - r).
  std::vector<int> kinks;
  for (int j = 1; j < J; ++j)
    if (slope(j) - slope(j - 1) > tol) kinks.push_back(j);
  const int k = static_cast<int>(kinks.size()) + 2;
  PlqForm& q = f.plq_;
  q.B.resize(k, 1);
  q.b.resize(k);
  q.lo.resize(k);
  q.hi.resize(k);
  q.M = Eigen::MatrixXd::Zero(k, k);
  for (int i = 0; i < k - 2; ++i) {
    const int j = kinks[i];
    q.B(i, 0) = 1.0;
    q.b(i) = knots(j);
    q.lo(i) = 0.0;
    q.hi(i) = slope(j) - slope(j - 1);
  }
  q.B(k - 2, 0) = 1.0;
  q.b(k - 2) = knots(J);
  q.B(k - 1, 0) = -1.0;
  q.b(k - 1) = -knots(0);
  q.lo(k - 2) = q.lo(k - 1) = 0.0;
  q.hi(k - 2) = q.hi(k - 1) = kInfinity;
  q.p = Eigen::VectorXd::Constant(1, slope(0));
  q.p0 = values(0) - slope(0) * knots(0);
  f.conj_lo_ = Eigen::VectorXd::Constant(1, -kInfinity);
  f.conj_hi_ = Eigen::VectorXd::Constant(1, kInfinity);
  return f;
}

std::string Penalty::Name() const {
  switch (kind_) {
    case Kind::kQuadratic:
      return "quadratic";
    case Kind::kL1:
      return "l1";
    case Kind::kHuber:
      return "huber";
    case Kind::kVapnik:
      return "vapnik";
    case Kind::kQuantile:
      return "quantile";
    case Kind::kBoxMonitoring:
      return "box";
    case Kind::kPiecewiseLinear:
      return "piecewise_linear";
  }
  return "?";
}

double Penalty::BoxMonitoringValue(const Eigen::Ref<const Eigen::VectorXd>& r) const {
  const Eigen::MatrixXd& M = matrix_;
  const int m = dim_;
  // One coordinate: sup_{lo <= u <= hi} { u a - 1/2 mii u^2 }.
  auto best = [&](int i, double a) {
    if (M(i, i) > 0) return std::clamp(a / M(i, i), box_lo_(i), box_hi_(i));
    return a > 0 ? box_hi_(i) : (a < 0 ? box_lo_(i) : 0.0);
  };
  Eigen::VectorXd u(m);
  if (plq_.diagonal_M) {
    for (int i = 0; i < m; ++i) u(i) = best(i, r(i));
  } else {
    // Coordinate ascent on the concave box QP; exact maximiser per coordinate, converges for PSD M.
    u.setZero();
    for (int i = 0; i < m; ++i) u(i) = std::clamp(0.0, box_lo_(i), box_hi_(i));
    for (int sweep = 0; sweep < 100000; ++sweep) {
      double change = 0;
      for (int i = 0; i < m; ++i) {
        const double a = r(i) - M.row(i).dot(u) + M(i, i) * u(i);
        const double ui = best(i, a);
        change = std::max(change, std::abs(ui - u(i)) / (1 + std::abs(ui)));
        u(i) = ui;
      }
      if (change < 1e-15) break;
    }
  }
  if (!u.allFinite()) return kInfinity;
  return r.dot(u) - 0.5 * u.dot(M * u);
}

double Penalty::Value(const Eigen::Ref<const Eigen::VectorXd>& r, double domain_tolerance) const {
  IDENT_REQUIRE(r.size() == dim_, "{} penalty has dimension {} but the residual has {} entries", Name(), dim_,
                r.size());
  double sum = 0;
  switch (kind_) {
    case Kind::kQuadratic:
      return HalfQuadraticForm(precision_, r);
    case Kind::kL1:
      return r.cwiseAbs().sum();
    case Kind::kHuber:
      for (int i = 0; i < dim_; ++i) {
        const double a = std::abs(r(i)), k = parameter_;
        sum += a <= k ? 0.5 * a * a : k * a - 0.5 * k * k;
      }
      return sum;
    case Kind::kVapnik:
      for (int i = 0; i < dim_; ++i) sum += std::max(0.0, std::abs(r(i)) - parameter_);
      return sum;
    case Kind::kQuantile:
      for (int i = 0; i < dim_; ++i) sum += r(i) >= 0 ? parameter_ * r(i) : (parameter_ - 1) * r(i);
      return sum;
    case Kind::kBoxMonitoring:
      return BoxMonitoringValue(r);
    case Kind::kPiecewiseLinear: {
      const int last = static_cast<int>(knots_.size()) - 1;
      double x = r(0);
      if (x < knots_(0)) {
        if (x < knots_(0) - domain_tolerance) return kInfinity;
        x = knots_(0);
      }
      if (x > knots_(last)) {
        if (x > knots_(last) + domain_tolerance) return kInfinity;
        x = knots_(last);
      }
      const int j =
          std::clamp(static_cast<int>(std::upper_bound(knots_.data(), knots_.data() + last + 1, x) - knots_.data()) - 1,
                     0, last - 1);
      const double t = (x - knots_(j)) / (knots_(j + 1) - knots_(j));
      return (1 - t) * values_(j) + t * values_(j + 1);
    }
  }
  return kInfinity;
}

double Penalty::Conjugate(const Eigen::Ref<const Eigen::VectorXd>& v) const {
  IDENT_REQUIRE(v.size() == dim_, "{} penalty has dimension {} but the dual vector has {} entries", Name(), dim_,
                v.size());
  for (int i = 0; i < dim_; ++i)
    if (!(v(i) >= conj_lo_(i) && v(i) <= conj_hi_(i))) return kInfinity;
  switch (kind_) {
    case Kind::kQuadratic:
      return HalfQuadraticForm(matrix_, v);  // (1/2 r'C^-1 r)* = 1/2 v'C v
    case Kind::kL1:
      return 0.0;  // indicator of [-1, 1]^m
    case Kind::kHuber:
      return 0.5 * v.squaredNorm();  // Lemma 2.8, U = [-kappa, kappa]
    case Kind::kVapnik:
      return parameter_ * v.cwiseAbs().sum();  // eps |v| on [-1, 1]
    case Kind::kQuantile:
      return 0.0;  // indicator of [tau-1, tau]
    case Kind::kBoxMonitoring:
      return HalfQuadraticForm(matrix_, v);  // Lemma 2.8
    case Kind::kPiecewiseLinear: {
      // sup_r { v r - rho(r) } is attained at a knot: rho* (v) = max_j { v k_j - rho(k_j) }.
      double best = -kInfinity;
      for (int j = 0; j < knots_.size(); ++j) best = std::max(best, v(0) * knots_(j) - values_(j));
      return best;
    }
  }
  return kInfinity;
}

Eigen::VectorXd Penalty::ConjugateGradient(const Eigen::Ref<const Eigen::VectorXd>& v) const {
  Eigen::VectorXd g(dim_);
  ConjugateGradient(v, g);
  return g;
}

void Penalty::ConjugateGradient(const Eigen::Ref<const Eigen::VectorXd>& v, Eigen::Ref<Eigen::VectorXd> g) const {
  IDENT_REQUIRE(v.size() == dim_ && g.size() == dim_,
                "{} penalty has dimension {} but the dual vector has {} entries (output {})", Name(), dim_, v.size(),
                g.size());
  g.setZero();
  switch (kind_) {
    case Kind::kQuadratic:
    case Kind::kBoxMonitoring:
      for (int j = 0; j < dim_; ++j)
        for (int i = 0; i < dim_; ++i) g(i) += matrix_(i, j) * v(j);
      break;
    case Kind::kHuber:
      g = v;
      break;
    case Kind::kVapnik:
      for (int i = 0; i < dim_; ++i) g(i) = v(i) > 0 ? parameter_ : (v(i) < 0 ? -parameter_ : 0.0);
      break;
    case Kind::kL1:
    case Kind::kQuantile:
      break;
    case Kind::kPiecewiseLinear: {
      int arg = 0;
      for (int j = 1; j < knots_.size(); ++j)
        if (v(0) * knots_(j) - values_(j) > v(0) * knots_(arg) - values_(arg)) arg = j;
      g(0) = knots_(arg);
      break;
    }
  }
}

bool Penalty::ConjugateIsDifferentiableNear(const Eigen::Ref<const Eigen::VectorXd>& v, double tolerance) const {
  IDENT_REQUIRE(v.size() == dim_, "{} penalty has dimension {} but the dual vector has {} entries", Name(), dim_,
                v.size());
  IDENT_REQUIRE(tolerance >= 0, "tolerance = {}; need >= 0", tolerance);
  if (kind_ == Kind::kPiecewiseLinear) {
    // rho* (v) = max_j {v k_j - rho(k_j)} has a kink exactly where v equals the slope of a piece of rho
    // (two adjacent knots attain the max); pieces with equal slopes form one piece.
    const int last = static_cast<int>(knots_.size()) - 1;
    for (int j = 0; j < last; ++j) {
      const double slope = (values_(j + 1) - values_(j)) / (knots_(j + 1) - knots_(j));
      if (std::abs(v(0) - slope) <= tolerance) return false;
    }
    return true;
  }
  // Every other penalty here has rho* smooth on the interior of the box dom rho*: the normal cone of
  // the box adds a ray at a finite bound.
  for (int i = 0; i < dim_; ++i) {
    if (v(i) - conj_lo_(i) <= tolerance || conj_hi_(i) - v(i) <= tolerance) return false;
    if (kind_ == Kind::kVapnik && parameter_ > 0 && std::abs(v(i)) <= tolerance) return false;  // eps |v_i|
  }
  return true;
}

}  // namespace ident::models
