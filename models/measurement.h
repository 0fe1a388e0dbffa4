// Log-concave measurement functions f_M(y, x) (Henningsson & Åström 2006, sec. IV, V; example 1).
//
// Provides:
//   MeasurementFunction     log f_M(y, x) for a scalar reading y, log-concave in x for every y, and its
//                           strength of log-concavity Q(y): f_M(y, ·) ∈ LC(Q(y))        [1, Def. 2]
//   ProjectedMeasurement    f_M(y, x) = g(y, c'x) (depends on x only through s = c'x), with the exact
//                           moments of the tilted density g(y, s) N(s; m, v) / Z        (Tilt())
//   GaussianMeasurement     y = c'x + e, e ~ N(0, r)                          LC(c c'/r), closed form
//   ThresholdSensor         y = sign(c'x) if |c'x| ≥ T else 0  (the MEMS sensor, [1, sec. II]) LC(0)
//   UniformQuantizer        y = Δ·round(c'x/Δ)                                          LC(0)
//   OptimalQuantizer        f_M(y, x) = f(c'x − y), y ∈ Z, f of [1, example 1]        LC(8 ln2 c c')
//   LaplaceMeasurement      y = c'x + e, e ~ Laplace(0, b)                              LC(0)
//
// Tilted moments: for threshold and quantiser the interval-truncated normal in closed form (normal tail
// in log space, Boost.Math erf/erfc); otherwise adaptive Gauss–Kronrod quadrature around the mode of
// the (log-concave, hence unimodal) tilted density. The multivariate posterior then follows exactly:
// with k = P c / (c'Pc),  m' = m + k (μ_s − c'm),  P' = P − k k' (c'Pc − v_s)   (ident/observers/lc_gaussian_filter.h).
//
// Example:
//   ident::models::ThresholdSensor sensor(Eigen::Vector2d(1, 0), /*threshold=*/1.0);
//   auto t = sensor.Tilt(/*y=*/0, /*mean=*/0.3, /*variance=*/0.5);   // N(0.3, 0.5) truncated to (−1, 1)
//   double p = std::exp(t.log_normalizer);                            // P(y = 0)
//
// [1] T. Henningsson, K. J. Åström, "Log-concave Observers", MTNS 2006.
#pragma once

#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <string>

#include <Eigen/Core>

namespace ident::models {

// Moments of the tilted density g(y, s) N(s; m, v) / Z. ok = false when Z underflows to 0 (the reading
// is impossible under the prior to double precision); the other fields are then NaN.
struct TiltedMoments {
  double log_normalizer = std::numeric_limits<double>::quiet_NaN();  // log Z
  double mean = std::numeric_limits<double>::quiet_NaN();
  double variance = std::numeric_limits<double>::quiet_NaN();
  bool ok = false;
};

class MeasurementFunction {
 public:
  virtual ~MeasurementFunction() = default;
  virtual std::string name() const = 0;
  virtual int num_states() const = 0;
  // log f_M(y, x); −∞ outside the support. y must satisfy IsValidOutput(y).
  virtual double LogLikelihood(double y, const Eigen::Ref<const Eigen::VectorXd>& x) const = 0;
  // Q(y) with f_M(y, ·) ∈ LC(Q(y)) [1, Def. 2]; the zero matrix when only log-concave.
  virtual Eigen::MatrixXd Strength(double y) const = 0;
  virtual bool IsValidOutput(double y) const = 0;
};

class ProjectedMeasurement : public MeasurementFunction {
 public:
  explicit ProjectedMeasurement(Eigen::VectorXd c);
  const Eigen::VectorXd& c() const { return c_; }
  int num_states() const final { return static_cast<int>(c_.size()); }
  double LogLikelihood(double y, const Eigen::Ref<const Eigen::VectorXd>& x) const final {
    return LogLikelihoodScalar(y, c_.dot(x));
  }
  Eigen::MatrixXd Strength(double y) const final { return ScalarStrength(y) * c_ * c_.transpose(); }

  // log g(y, s).
  virtual double LogLikelihoodScalar(double y, double s) const = 0;
  // q(y) with g(y, ·) ∈ LC(q(y)).
  virtual double ScalarStrength(double y) const = 0;
  // Exact moments of g(y, s) N(s; mean, variance) / Z; variance > 0. Default: QuadratureTilt.
  virtual TiltedMoments Tilt(double y, double mean, double variance) const;
  // Adaptive Gauss–Kronrod quadrature of the same moments (also the reference for closed forms).
  TiltedMoments QuadratureTilt(double y, double mean, double variance) const;

 protected:
  // Support [lo, hi] of g(y, ·) and up to 3 interior kinks (NaN = unused), for the quadrature.
  struct Pieces {
    double lo = -std::numeric_limits<double>::infinity();
    double hi = std::numeric_limits<double>::infinity();
    std::array<double, 3> kinks{std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::quiet_NaN(),
                                std::numeric_limits<double>::quiet_NaN()};
  };
  virtual Pieces SupportPieces(double y) const {
    (void)y;
    return {};
  }

 private:
  Eigen::VectorXd c_;
};

// N(s; m, v) truncated to [lo, hi] (lo may be −∞, hi may be +∞): closed form, stable in both tails.
// Throws InvalidArgument unless mean is finite and 0 < variance < ∞. An interval without mass — empty
// or a single point (lo ≥ hi), a NaN bound, or one so narrow or so far out that Z underflows (also
// after standardising: (lo − m)/√v = (hi − m)/√v) — gives ok = false, never NaN moments with ok = true.
TiltedMoments TruncatedNormalMoments(double mean, double variance, double lo, double hi);
// The standard normal N(0, 1) truncated to [a, b]. Total: ok = false (and NaN moments) if a ≥ b
// (e.g. a = b = 0, a = b = ±∞), a or b is NaN, or Z underflows; otherwise finite log Z, a mean in
// [a, b] and a variance ≥ 0.
TiltedMoments StandardTruncatedMoments(double a, double b);
// log P(Z > x) for standard normal Z, accurate far into the upper tail.
double LogNormalTail(double x);
// log φ(x) of the standard normal density (−∞ at ±∞).
double LogNormalDensity(double x);

class GaussianMeasurement final : public ProjectedMeasurement {
 public:
  GaussianMeasurement(Eigen::VectorXd c, double noise_variance);
  std::string name() const override { return "gaussian"; }
  double LogLikelihoodScalar(double y, double s) const override;
  double ScalarStrength(double) const override { return 1.0 / r_; }
  TiltedMoments Tilt(double y, double mean, double variance) const override;
  bool IsValidOutput(double y) const override { return std::isfinite(y); }
  double noise_variance() const { return r_; }

 private:
  double r_;
};

// Interval readings: y ↦ s ∈ [lo(y), hi(y)]; g = indicator of the interval.
class IntervalMeasurement : public ProjectedMeasurement {
 public:
  using ProjectedMeasurement::ProjectedMeasurement;
  virtual std::pair<double, double> Interval(double y) const = 0;
  double LogLikelihoodScalar(double y, double s) const override;
  double ScalarStrength(double) const override { return 0.0; }
  TiltedMoments Tilt(double y, double mean, double variance) const override;

 protected:
  Pieces SupportPieces(double y) const override;
};

// y = sign(s) if |s| ≥ T, else 0   [1, sec. II]. y ∈ {−1, 0, 1}.
class ThresholdSensor final : public IntervalMeasurement {
 public:
  ThresholdSensor(Eigen::VectorXd c, double threshold);
  std::string name() const override { return "threshold"; }
  std::pair<double, double> Interval(double y) const override;
  bool IsValidOutput(double y) const override { return y == -1.0 || y == 0.0 || y == 1.0; }
  double threshold() const { return threshold_; }
  // The reading a true state produces.
  double Measure(const Eigen::Ref<const Eigen::VectorXd>& x) const;

 private:
  double threshold_;
};

// y = Δ·round(s/Δ) (mid-tread); y ∈ ΔZ, s ∈ [y − Δ/2, y + Δ/2).
class UniformQuantizer final : public IntervalMeasurement {
 public:
  UniformQuantizer(Eigen::VectorXd c, double step);
  std::string name() const override { return "quantizer"; }
  std::pair<double, double> Interval(double y) const override;
  bool IsValidOutput(double y) const override;
  double Measure(const Eigen::Ref<const Eigen::VectorXd>& x) const;

 private:
  double step_;
};

// [1, example 1]: f(x) = 2^(−4x²) for |x| ≤ 1/2, 1 − 2^(−4(1−|x|)²) for 1/2 < |x| ≤ 1, else 0;
// Σ_k f(x − k) = 1 and f ∈ LC(8 ln 2). f_M(y, x) = f(c'x − y), y ∈ Z.
class OptimalQuantizer final : public ProjectedMeasurement {
 public:
  explicit OptimalQuantizer(Eigen::VectorXd c);
  std::string name() const override { return "optimal-quantizer"; }
  static double Density(double x);     // f(x)
  static double LogDensity(double x);  // log f(x)
  double LogLikelihoodScalar(double y, double s) const override { return LogDensity(s - y); }
  double ScalarStrength(double) const override { return 8.0 * std::log(2.0); }
  bool IsValidOutput(double y) const override { return std::isfinite(y) && y == std::round(y); }

 protected:
  Pieces SupportPieces(double y) const override;
};

// y = s + e, e ~ Laplace(0, b): g = exp(−|y − s|/b) / (2b).
class LaplaceMeasurement final : public ProjectedMeasurement {
 public:
  LaplaceMeasurement(Eigen::VectorXd c, double scale);
  std::string name() const override { return "laplace"; }
  double LogLikelihoodScalar(double y, double s) const override;
  double ScalarStrength(double) const override { return 0.0; }
  bool IsValidOutput(double y) const override { return std::isfinite(y); }

 protected:
  Pieces SupportPieces(double y) const override;

 private:
  double b_;
};

}  // namespace ident::models
