#include "ident/workflow/residual_analysis.h"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>
#include <boost/math/distributions/chi_squared.hpp>

#include "common/error.h"

namespace ident::workflow {
namespace {

void Centre(std::vector<double>& v) {
  double mean = 0;
  for (double x : v) mean += x;
  mean /= static_cast<double>(v.size());
  for (double& x : v) x -= mean;
}

std::vector<double> Centred(std::vector<double> v) {
  Centre(v);
  return v;
}

// s(τ) = Σ_{t ≥ τ} x(t) y(t − τ) for τ = first … last. The sums run block by block, every lag on one block
// of x while it is in cache: one pass over memory instead of one per lag.
std::vector<double> LaggedSums(const std::vector<double>& x_in, const std::vector<double>& y_in, int first, int last) {
  constexpr Eigen::Index kBlock = 2048;
  const auto n = static_cast<Eigen::Index>(x_in.size());
  const Eigen::Map<const Eigen::VectorXd> x(x_in.data(), n), y(y_in.data(), n);
  std::vector<double> s(static_cast<std::size_t>(last - first + 1), 0.0);
  for (Eigen::Index begin = 0; begin < n; begin += kBlock) {
    const Eigen::Index end = std::min(n, begin + kBlock);
    for (int tau = first; tau <= last; ++tau) {
      const Eigen::Index t0 = std::max<Eigen::Index>(begin, tau);  // x(t) with t ≥ τ
      if (t0 < end)
        s[static_cast<std::size_t>(tau - first)] += x.segment(t0, end - t0).dot(y.segment(t0 - tau, end - t0));
    }
  }
  return s;
}

// r_ee and r_eu of centred sequences.
std::vector<double> CentredAutocorrelation(const std::vector<double>& e, int max_lag) {
  const double ee = LaggedSums(e, e, 0, 0)[0];
  std::vector<double> r = LaggedSums(e, e, 1, max_lag);
  for (double& v : r) v = ee > 0 ? v / ee : 0.0;
  return r;
}

std::vector<double> CentredCrossCorrelation(const std::vector<double>& e, const std::vector<double>& u, int max_lag) {
  const double norm = std::sqrt(LaggedSums(e, e, 0, 0)[0] * LaggedSums(u, u, 0, 0)[0]);
  std::vector<double> r = LaggedSums(e, u, 0, max_lag);
  for (double& v : r) v = norm > 0 ? v / norm : 0.0;
  return r;
}

}  // namespace

std::vector<double> Autocorrelation(const std::vector<double>& e_in, int max_lag) {
  IDENT_REQUIRE(max_lag >= 1 && static_cast<std::size_t>(max_lag) < e_in.size(),
                "max_lag = {}; need 1 <= max_lag < {} (the number of residuals)", max_lag, e_in.size());
  return CentredAutocorrelation(Centred(e_in), max_lag);
}

std::vector<double> CrossCorrelation(const std::vector<double>& e_in, const std::vector<double>& u_in, int max_lag) {
  IDENT_REQUIRE(e_in.size() == u_in.size(), "{} residuals but {} input samples", e_in.size(), u_in.size());
  IDENT_REQUIRE(max_lag >= 0 && static_cast<std::size_t>(max_lag) < e_in.size(), "max_lag = {}; need 0 <= max_lag < {}",
                max_lag, e_in.size());
  return CentredCrossCorrelation(Centred(e_in), Centred(u_in), max_lag);
}

int ResidualAnalysis::OutsideAuto() const {
  int n = 0;
  for (double r : autocorrelation) n += std::abs(r) > band;
  return n;
}

int ResidualAnalysis::OutsideCross(std::size_t input) const {
  int n = 0;
  for (double r : cross_correlation[input]) n += std::abs(r) > band;
  return n;
}

namespace {
double Q(const std::vector<double>& r, int n) {
  double s = 0;
  for (double x : r) s += x * x;
  return n * s;
}
double Chi2Quantile99(std::size_t dof) {
  return boost::math::quantile(boost::math::chi_squared(static_cast<double>(dof)), 0.99);
}
}  // namespace

double ResidualAnalysis::QAuto() const { return Q(autocorrelation, samples); }
double ResidualAnalysis::QCross(std::size_t input) const { return Q(cross_correlation[input], samples); }
double ResidualAnalysis::QAutoLimit() const { return Chi2Quantile99(autocorrelation.size()); }
double ResidualAnalysis::QCrossLimit() const { return Chi2Quantile99(autocorrelation.size() + 1); }

bool ResidualAnalysis::Independent() const {
  for (std::size_t i = 0; i < cross_correlation.size(); ++i)
    if (QCross(i) > QCrossLimit()) return false;
  return true;
}

std::string ResidualAnalysis::Verdict() const {
  if (!applies) return "verdict: none (a static regression's rows need not be a time series)";
  std::string whiteness =
      White() ? "residuals look white" : "residuals are NOT white (the noise model misses dynamics)";
  std::string independence = Independent() ? "independent of the input"
                                           : "correlated with the input (the model misses input dynamics or delay)";
  return fmt::format("verdict: {}, {}", whiteness, independence);
}

ResidualAnalysis AnalyseResiduals(const io::DataTable& data, Segment segment, DataSource& source,
                                  const Eigen::VectorXd& theta, int max_lag) {
  std::vector<int> input_columns = source.used_columns();
  input_columns.pop_back();  // the output is last
  Eigen::VectorXd z(source.num_parameters());
  Eigen::VectorXd row(data.values.cols());
  std::vector<double> e;
  std::vector<std::vector<double>> u(input_columns.size());
  e.reserve(static_cast<std::size_t>(segment.count));
  for (std::vector<double>& column : u) column.reserve(static_cast<std::size_t>(segment.count));
  source.Reset();
  source.SetEstimate(theta);
  for (int r = segment.first; r < segment.first + segment.count; ++r) {
    if (r > segment.first && data.StartsExperiment(r)) source.Restart();
    row = data.values.row(r).transpose();
    const double y = row(source.output_column());
    bool inputs_finite = true;
    for (int column : input_columns) inputs_finite = inputs_finite && std::isfinite(row(column));
    if (source.Regressor(row, z) && std::isfinite(y) && AllFinite(z) && inputs_finite) {
      e.push_back(y - theta.dot(z));
      for (std::size_t i = 0; i < input_columns.size(); ++i) u[i].push_back(row(input_columns[i]));
    }
    source.PushOutput(y);
  }
  ResidualAnalysis a;
  a.samples = static_cast<int>(e.size());
  IDENT_REQUIRE(a.samples > max_lag + 1, "{}: {} residuals are too few for correlations up to lag {}", data.source,
                a.samples, max_lag);
  a.band = 2.58 / std::sqrt(static_cast<double>(a.samples));
  a.applies = source.dynamic();
  if (!a.applies) return a;
  Centre(e);  // in place: a record's residuals and inputs are large
  a.autocorrelation = CentredAutocorrelation(e, max_lag);
  for (std::size_t i = 0; i < input_columns.size(); ++i) {
    a.input_names.push_back(data.names[static_cast<std::size_t>(input_columns[i])]);
    Centre(u[i]);
    a.cross_correlation.push_back(CentredCrossCorrelation(e, u[i], max_lag));
  }
  return a;
}

}  // namespace ident::workflow
