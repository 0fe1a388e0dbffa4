// Residual analysis of a fitted model on a data segment (the end of `ident fit`'s report).
//
// With one-step residuals e(t) = y(t) − θ̂'z(t) over the N scored samples (means removed):
//   r_ee(τ) = Σ_t e(t)e(t−τ) / Σ_t e(t)²,                      τ = 1 … L   (whiteness)
//   r_eu(τ) = Σ_t e(t)u(t−τ) / √(Σ e(t)² · Σ u(t)²),          τ = 0 … L   (independence of input u)
// Under the null hypothesis (white residuals, independent of past inputs) each r is approximately
// N(0, 1/N): the 99 % band is ±2.58/√N (Ljung, System Identification, 2nd ed., §16.6). The verdict
// uses the portmanteau statistics over all lags, each χ²-distributed under the null hypothesis:
//   Q_ee = N Σ_{τ=1..L} r_ee(τ)² ~ χ²(L),   Q_eu = N Σ_{τ=0..L} r_eu(τ)² ~ χ²(L+1)     (Ljung §16.6)
// and rejects at the 1 % level (Q above the 99 % quantile, from Boost.Math).
// Both tests ask about lags in time: they apply to dynamic structures (ARX, ARMAX, OE, BJ) only. For a
// static regression the rows need not be a time series, and the analysis holds the residual count alone
// (applies false, no correlations).
//
// Example:
//   ResidualAnalysis a = AnalyseResiduals(table, validation, *source, theta, 20);
//   fmt::print("{}\n", a.Verdict());
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "ident/io/csv.h"
#include "ident/workflow/data_source.h"
#include "ident/workflow/fit.h"

namespace ident::workflow {

struct ResidualAnalysis {
  bool applies = true;                                 // the rows are a time series (dynamic structure)
  int samples = 0;                                     // N
  double band = 0;                                     // 2.58/√N
  std::vector<double> autocorrelation;                 // r_ee(1..L)
  std::vector<std::string> input_names;                // one per input (ARX) or regressor column (static)
  std::vector<std::vector<double>> cross_correlation;  // r_eu_i(0..L)
  int OutsideAuto() const;                             // lags of r_ee outside the band
  int OutsideCross(std::size_t input) const;
  double QAuto() const;  // Q_ee
  double QCross(std::size_t input) const;
  double QAutoLimit() const;   // 99 % quantile of χ²(L)
  double QCrossLimit() const;  // 99 % quantile of χ²(L+1)
  bool White() const { return QAuto() <= QAutoLimit(); }
  bool Independent() const;     // every input: Q_eu below its limit
  std::string Verdict() const;  // one line
};

// Correlation coefficients as defined above for plain sequences (exposed for tests).
std::vector<double> Autocorrelation(const std::vector<double>& e, int max_lag);
std::vector<double> CrossCorrelation(const std::vector<double>& e, const std::vector<double>& u, int max_lag);

// One-step residuals of θ on the segment and their correlations up to max_lag (>= 1).
ResidualAnalysis AnalyseResiduals(const io::DataTable& data, Segment segment, DataSource& source,
                                  const Eigen::VectorXd& theta, int max_lag = 20);

}  // namespace ident::workflow
