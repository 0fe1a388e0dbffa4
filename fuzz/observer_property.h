// Properties of the recursive state observers fed arbitrary doubles: the square-root Kalman filter
// (ident/observers/kalman_filter.h) and the log-concave Gaussian filter (ident/observers/lc_gaussian_filter.h).
// Input: 1 byte n (1..3 states), then operations until the bytes run out: 1 byte op
//   even -> Predict with A (n×n), B (n×1), P_N = G G' (G n×n; or, if the op's bit 1 is set, P_N taken raw),
//           and u;
//   odd  -> Correct with c (n), then for Kalman r and y; for the LC filter a measurement kind (Gaussian,
//           threshold, uniform quantiser, Laplace) with its parameter and y.
// Each number is either an arbitrary bit pattern (NaN, ±Inf, subnormals, ±1e308 all occur) or, most of
// the time, a tame value k/16 (k a signed byte), so that long healthy runs happen too.
// Holds if, after every operation:
//   updated     -> the mean, the covariance (factor) and the log-likelihood are finite;
//   not updated -> mean, covariance and log-likelihood are bit-for-bit unchanged.
// Predict and Correct are noexcept: a throw would terminate the process, which libFuzzer reports.
// Invalid measurement parameters are refused by the measurement's constructor (InvalidArgument), which
// the property accepts and skips.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

#include <Eigen/Core>

#include "common/error.h"
#include "fuzz/fuzz_util.h"
#include "ident/observers/kalman_filter.h"
#include "ident/observers/lc_gaussian_filter.h"
#include "models/measurement.h"
#include "models/state_space.h"

namespace ident::fuzz {

namespace observer_detail {

// A tame value k/16 three times in four, else any double.
inline double Value(ByteReader& in) {
  const std::uint8_t kind = in.Byte();
  if (kind % 4 == 0) return in.Double();
  return static_cast<std::int8_t>(in.Byte()) / 16.0;
}

inline void Fill(ByteReader& in, Eigen::Ref<Eigen::MatrixXd> m) {
  for (Eigen::Index j = 0; j < m.cols(); ++j)
    for (Eigen::Index i = 0; i < m.rows(); ++i) m(i, j) = Value(in);
}

// Reads A, B, P_N and u for one Predict.
inline void ReadPredict(ByteReader& in, bool raw_noise, models::LinearStateSpace& model, Eigen::VectorXd& u) {
  Fill(in, model.A);
  Fill(in, model.B);
  Fill(in, model.process_noise);
  if (!raw_noise) model.process_noise = (model.process_noise * model.process_noise.transpose()).eval();
  u(0) = Value(in);
}

// Reads one projected measurement on c'x (kind, parameter) and its reading y. Returns nullptr when the
// measurement's constructor refuses the parameter (the documented boundary check); y is read either way.
inline std::unique_ptr<models::ProjectedMeasurement> ReadMeasurement(ByteReader& in, const Eigen::VectorXd& c,
                                                                     double& y) {
  const std::uint8_t kind = in.Byte() % 4;
  const double parameter = Value(in);
  y = Value(in);
  try {
    switch (kind) {
      case 0:
        return std::make_unique<models::GaussianMeasurement>(c, parameter);
      case 1:
        return std::make_unique<models::ThresholdSensor>(c, parameter);
      case 2:
        return std::make_unique<models::UniformQuantizer>(c, parameter);
      default:
        return std::make_unique<models::LaplaceMeasurement>(c, parameter);
    }
  } catch (const InvalidArgument&) {
    return nullptr;
  }
}

}  // namespace observer_detail

inline Eigen::MatrixXd CovarianceOf(const KalmanFilter& f) { return f.covariance_factor(); }
inline Eigen::MatrixXd CovarianceOf(const LcGaussianFilter& f) { return f.covariance(); }

// Runs the operations on `filter`; `correct(in, c)` reads the rest of a Correct and performs it
// (kSkipped if the measurement was refused at construction).
template <class Filter, class CorrectFn>
std::string RunObserverProperty(ByteReader& in, int n, Filter& filter, CorrectFn&& correct) {
  using namespace observer_detail;
  models::LinearStateSpace model{Eigen::MatrixXd(n, n), Eigen::MatrixXd(n, 1), Eigen::MatrixXd(n, n)};
  Eigen::VectorXd u(1), c(n);
  while (in.remaining() > 0) {
    const std::uint8_t op = in.Byte();
    const Eigen::VectorXd mean0 = filter.mean();
    const Eigen::MatrixXd cov0 = CovarianceOf(filter);
    const double loglik0 = filter.log_likelihood();
    StepReport report;
    if (op % 2 == 0) {
      ReadPredict(in, (op & 2) != 0, model, u);
      report = filter.Predict(model, u);
    } else {
      Fill(in, c);
      report = correct(in, c);
    }
    if (report.updated()) {
      if (!filter.mean().allFinite()) return "an updated mean is finite";
      if (!CovarianceOf(filter).allFinite()) return "an updated covariance is finite";
      if (std::isnan(filter.log_likelihood())) return "the log-likelihood is not NaN";
    } else if (!(filter.mean() == mean0 && CovarianceOf(filter) == cov0 &&
                 (filter.log_likelihood() == loglik0 ||
                  (std::isnan(loglik0) && std::isnan(filter.log_likelihood()))))) {
      return "a step not taken leaves the state unchanged";
    }
  }
  return {};
}

inline std::string KalmanProperty(const std::uint8_t* data, std::size_t size) {
  ByteReader in(data, size);
  const int n = 1 + in.Byte() % 3;
  KalmanFilter filter(Eigen::VectorXd::Zero(n), Eigen::MatrixXd::Identity(n, n));
  return RunObserverProperty(in, n, filter, [&](ByteReader& r, const Eigen::VectorXd& c) {
    const double noise = observer_detail::Value(r);
    const double y = observer_detail::Value(r);
    return filter.Correct(c, noise, y);
  });
}

inline std::string LcGaussianProperty(const std::uint8_t* data, std::size_t size) {
  ByteReader in(data, size);
  const int n = 1 + in.Byte() % 3;
  LcGaussianFilter filter(Eigen::VectorXd::Zero(n), Eigen::MatrixXd::Identity(n, n));
  return RunObserverProperty(in, n, filter, [&](ByteReader& r, const Eigen::VectorXd& c) {
    double y;
    const std::unique_ptr<models::ProjectedMeasurement> m = observer_detail::ReadMeasurement(r, c, y);
    if (!m) return StepReport{StepStatus::kSkipped};  // refused at the boundary, as documented
    return filter.Correct(*m, y);
  });
}

}  // namespace ident::fuzz
