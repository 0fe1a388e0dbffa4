// Convex penalties: negative log-densities f_t, g_t of log-concave noise for MAP smoothing
// (Bassett, Casey & Wets, "Log-Concave Duality in Estimation and Control" [BCW], Prop. 2.1).
//
// Provides ident::models::Penalty, a value type for one convex penalty rho: R^m -> (-inf, +inf]:
//   Quadratic(C)          rho(r) = 1/2 r' C^-1 r                      (Gaussian, covariance C)
//   L1(m)                 rho(r) = sum |r_i|                           (Laplace)
//   Huber(kappa, m)       rho(r) = sum { r_i^2/2 if |r_i| <= kappa, kappa |r_i| - kappa^2/2 else }
//   Vapnik(eps, m)        rho(r) = sum max(0, |r_i| - eps)             (epsilon-insensitive)
//   Quantile(tau, m)      rho(r) = sum { tau r_i if r_i >= 0, (tau - 1) r_i else }
//   BoxMonitoring(lo,hi,M)  rho(r) = sup_{lo <= u <= hi} { r'u - 1/2 u'M u }   ([BCW] sec. 2, PLQ case)
//   PiecewiseLinear(k, v) rho linear between knots k_0 < ... < k_J with rho(k_j) = v_j, +inf outside
//                         [k_0, k_J] (the -log of a log-concave MLE density; must be convex)
// Each penalty exposes
//   Value(r)        rho(r) (+inf outside the domain),
//   Conjugate(v)    rho*(v) = sup_r { v'r - rho(r) } in closed form (Lemma 2.8 for monitoring functions),
//   ConjugateGradient(v)  an element of d rho*(v) (= the r attaining the sup; unique where rho* is
//                   differentiable), used to reconstruct w* from the dual y* ([BCW] sec. 3),
//   plq()           the piecewise linear-quadratic (PLQ) form the interior-point smoother needs
//                   (Aravkin, Burke & Pillonetto, JMLR 14 (2013) [ABP], eq. (3.1), with a box U):
//     rho(r) = p'r + p0 + sup_{lo <= u <= hi} { u'(B r - b) - 1/2 u'M u }.
//
// Example:
//   auto g = ident::models::Penalty::Huber(1.5);
//   double value = g.Value(Eigen::VectorXd::Constant(1, 3.0));      // 1.5*3 - 1.125 = 3.375
//   double conj = g.Conjugate(Eigen::VectorXd::Constant(1, 0.5));   // 0.125
#pragma once

#include <limits>
#include <string>

#include <Eigen/Core>

namespace ident::models {

// rho(r) = p'r + p0 + sup_{lo <= u <= hi} { u'(B r - b) - 1/2 u'M u }   [ABP eq. (3.1)]
// B is k x m, b and lo/hi have k entries (bounds may be -inf/+inf), M is k x k positive semidefinite.
struct PlqForm {
  Eigen::MatrixXd B;
  Eigen::VectorXd b;
  Eigen::MatrixXd M;
  Eigen::VectorXd lo, hi;
  Eigen::VectorXd p;
  double p0 = 0.0;
  bool diagonal_M = true;  // M is diagonal (the solver then works coordinate-wise)
  int rows() const { return static_cast<int>(B.rows()); }
};

class Penalty {
 public:
  enum class Kind { kQuadratic, kL1, kHuber, kVapnik, kQuantile, kBoxMonitoring, kPiecewiseLinear };

  // Throws InvalidArgument (naming the parameter) for a non-SPD covariance, kappa <= 0, eps < 0,
  // tau outside (0, 1), lo > hi, M not PSD, non-increasing knots or a non-convex piecewise-linear rho.
  static Penalty Quadratic(const Eigen::MatrixXd& covariance);
  static Penalty L1(int dim = 1);
  static Penalty Huber(double kappa, int dim = 1);
  static Penalty Vapnik(double epsilon, int dim = 1);
  static Penalty Quantile(double tau, int dim = 1);
  // Needs M positive definite when a bound is infinite (otherwise dom rho is not full-dimensional).
  static Penalty BoxMonitoring(const Eigen::VectorXd& lo, const Eigen::VectorXd& hi, const Eigen::MatrixXd& M);
  static Penalty PiecewiseLinear(const Eigen::VectorXd& knots, const Eigen::VectorXd& values);

  Kind kind() const { return kind_; }
  int dim() const { return dim_; }
  std::string Name() const;  // "quadratic", "l1", "huber", ...

  // rho(r); +inf outside dom rho. Residuals outside dom rho by at most `domain_tolerance` (absolute)
  // are evaluated at the nearest point of the domain (used for interior-point iterates that sit on a
  // support boundary up to rounding).
  double Value(const Eigen::Ref<const Eigen::VectorXd>& r, double domain_tolerance = 0.0) const;
  // rho*(v); +inf outside dom rho*.
  double Conjugate(const Eigen::Ref<const Eigen::VectorXd>& v) const;
  // An element of the subdifferential of rho* at v (v must lie in dom rho*).
  Eigen::VectorXd ConjugateGradient(const Eigen::Ref<const Eigen::VectorXd>& v) const;
  // The same written into `out` (dim() entries; no allocation).
  void ConjugateGradient(const Eigen::Ref<const Eigen::VectorXd>& v, Eigen::Ref<Eigen::VectorXd> out) const;
  // True if rho* is differentiable at every point within `tolerance` (max norm) of v, so that
  // d rho*(v) = {ConjugateGradient(v)} is a single point and r is determined by v through v in d rho(r).
  // False near the points where d rho*(v) is a segment or a ray: a finite bound of dom rho* (l1,
  // Huber, quantile, box, Vapnik |v_i| = 1), v_i = 0 for Vapnik with epsilon > 0, and v equal to the
  // slope of a piece of a piecewise-linear rho (rho* = max_j {v k_j - rho(k_j)} has a kink there).
  bool ConjugateIsDifferentiableNear(const Eigen::Ref<const Eigen::VectorXd>& v, double tolerance) const;
  // dom rho* is the box [conjugate_lo, conjugate_hi] for every penalty here.
  const Eigen::VectorXd& conjugate_lo() const { return conj_lo_; }
  const Eigen::VectorXd& conjugate_hi() const { return conj_hi_; }

  const PlqForm& plq() const { return plq_; }

  // Parameters (as given to the factory).
  const Eigen::MatrixXd& matrix() const { return matrix_; }  // covariance (quadratic) or M (box)
  double parameter() const { return parameter_; }            // kappa, epsilon or tau
  const Eigen::VectorXd& knots() const { return knots_; }    // piecewise linear
  const Eigen::VectorXd& values() const { return values_; }  // piecewise linear

 private:
  Penalty(Kind kind, int dim) : kind_(kind), dim_(dim) {}
  double BoxMonitoringValue(const Eigen::Ref<const Eigen::VectorXd>& r) const;

  Kind kind_;
  int dim_;
  double parameter_ = 0.0;
  Eigen::MatrixXd matrix_;
  Eigen::MatrixXd precision_;  // C^-1 for quadratic
  Eigen::VectorXd knots_, values_, box_lo_, box_hi_;
  Eigen::VectorXd conj_lo_, conj_hi_;
  PlqForm plq_;
};

inline constexpr double kInfinity = std::numeric_limits<double>::infinity();

}  // namespace ident::models
