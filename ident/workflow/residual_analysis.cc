#include "ident/workflow/residual_analysis.h"

#include <cmath>

#include <fmt/format.h>
#include <boost/math/distributions/chi_squared.hpp>

#include "common/error.h"

namespace ident::workflow {
namespace {

std::vector<double> Centred(const std::vector<double>& v) {
  double mean = 0;
  for (double x : v) mean += x;
  mean /= static_cast<double>(v.size());
  std::vector<double> c(v);
  for (double& x : c) x -= mean;
  return c;
}

double SumSquares(const std::vector<double>& v) {
  double s = 0;
  for (double x : v) s += x * x;
  return s;
}

}  // namespace

std::vector<double> Autocorrelation(const std::vector<double>& e_in, int max_lag) {
  IDENT_REQUIRE(max_lag >= 1 && static_cast<std::size_t>(max_lag) < e_in.size(),
                "max_lag = {}; need 1 <= max_lag < {} (the number of residuals)", max_lag, e_in.size());
  const std::vector<double> e = Centred(e_in);
  const double ee = SumSquares(e);
  std::vector<double> r;
  for (int tau = 1; tau <= max_lag; ++tau) {
    double s = 0;
    for (std::size_t t = static_cast<std::size_t>(tau); t < e.size(); ++t)
      s += e[t] * e[t - static_cast<std::size_t>(tau)];
    r.push_back(ee > 0 ? s / ee : 0.0);
  }
  return r;
}

std::vector<double> CrossCorrelation(const std::vector<double>& e_in, const std::vector<double>& u_in, int max_lag) {
  IDENT_REQUIRE(e_in.size() == u_in.size(), "{} residuals but {} input samples", e_in.size(), u_in.size());
  IDENT_REQUIRE(max_lag >= 0 && static_cast<std::size_t>(max_lag) < e_in.size(), "max_lag = {}; need 0 <= max_lag < {}",
                max_lag, e_in.size());
  const std::vector<double> e = Centred(e_in), u = Centred(u_in);
  const double norm = std::sqrt(SumSquares(e) * SumSquares(u));
  std::vector<double> r;
  for (int tau = 0; tau <= max_lag; ++tau) {
    double s = 0;
    for (std::size_t t = static_cast<std::size_t>(tau); t < e.size(); ++t)
      s += e[t] * u[t - static_cast<std::size_t>(tau)];
    r.push_back(norm > 0 ? s / norm : 0.0);
  }
  return r;
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
  std::vector<double> e;
  std::vector<std::vector<double>> u(input_columns.size());
  source.Reset();
  for (int r = segment.first; r < segment.first + segment.count; ++r) {
    const Eigen::VectorXd row = data.values.row(r).transpose();
    const double y = row(source.output_column());
    if (source.Regressor(row, z) && std::isfinite(y) && z.allFinite() && row(input_columns).allFinite()) {
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
  a.autocorrelation = Autocorrelation(e, max_lag);
  for (std::size_t i = 0; i < input_columns.size(); ++i) {
    a.input_names.push_back(data.names[static_cast<std::size_t>(input_columns[i])]);
    a.cross_correlation.push_back(CrossCorrelation(e, u[i], max_lag));
  }
  return a;
}

}  // namespace ident::workflow
