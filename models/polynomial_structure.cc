#include "models/polynomial_structure.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "common/error.h"

namespace ident::models {
namespace {

ArxStructure CheckedArx(int na, std::vector<int> nb, std::vector<int> nk, int nc, int nd, int nf) {
  IDENT_REQUIRE(nc >= 0, "nc = {}; need nc >= 0", nc);
  IDENT_REQUIRE(nd >= 0, "nd = {}; need nd >= 0", nd);
  IDENT_REQUIRE(nf >= 0, "nf = {}; need nf >= 0", nf);
  IDENT_REQUIRE(nc + nd + nf >= 1, "nc = nd = nf = 0 is an ARX model, not ARMAX/OE/BJ");
  IDENT_REQUIRE(nf == 0 || na == 0,
                "na = {} with nf = {}: an output-error or Box-Jenkins model has no A polynomial (give na = 0)", na, nf);
  IDENT_REQUIRE(nd == 0 || nf >= 1, "nd = {} needs nf >= 1 (Box-Jenkins); ARMAX has C only", nd);
  IDENT_REQUIRE(nf == 0 || nb.size() == 1,
                "nf = {} with {} inputs: the recursive OE and Box-Jenkins estimators take one input (ARX and ARMAX "
                "take several)",
                nf, nb.size());
  IDENT_REQUIRE(nf == 0 || nb[0] >= 1, "nf = {} with nb = 0: an output-error model needs nb >= 1", nf);
  IDENT_REQUIRE(static_cast<long long>(nc) + nd + nf <= ArxStructure::kMaxParameters,
                "nc + nd + nf = {}; need at most {}", static_cast<long long>(nc) + nd + nf,
                ArxStructure::kMaxParameters);
  return ArxStructure(na, std::move(nb), std::move(nk));
}

}  // namespace

PolynomialStructure::PolynomialStructure(int na, std::vector<int> nb, std::vector<int> nk, int nc, int nd, int nf)
    : arx_(CheckedArx(na, std::move(nb), std::move(nk), nc, nd, nf)), nc_(nc), nd_(nd), nf_(nf) {
  IDENT_REQUIRE(static_cast<long long>(arx_.num_parameters()) + nc + nd + nf <= ArxStructure::kMaxParameters,
                "the model has {} parameters; need at most {}",
                static_cast<long long>(arx_.num_parameters()) + nc + nd + nf, ArxStructure::kMaxParameters);
  t0_ = std::max({arx_.first_regression_index(), nc_, nd_, nf_});
}

std::string PolynomialStructure::ToString() const {
  const auto& nb = arx_.nb();
  const auto& nk = arx_.nk();
  const std::string b = nb.size() == 1 ? fmt::format("{}", nb[0]) : fmt::format("[{}]", fmt::join(nb, ","));
  const std::string k = nk.size() == 1 ? fmt::format("{}", nk[0]) : fmt::format("[{}]", fmt::join(nk, ","));
  if (nf_ == 0) return fmt::format("ARMAX({},{},{},{})", na(), b, nc_, k);
  if (nc_ == 0 && nd_ == 0) return fmt::format("OE({},{},{})", b, nf_, k);
  return fmt::format("BJ({},{},{},{},{})", b, nc_, nd_, nf_, k);
}

std::vector<std::string> PolynomialStructure::ParameterNames() const {
  std::vector<std::string> names = arx_.ParameterNames();
  for (int k = 1; k <= nc_; ++k) names.push_back(fmt::format("c{}", k));
  for (int k = 1; k <= nd_; ++k) names.push_back(fmt::format("d{}", k));
  for (int k = 1; k <= nf_; ++k) names.push_back(fmt::format("f{}", k));
  return names;
}

bool MonicStable(const double* p, int n, double* work) {
  // Σ|a_j| < 1 suffices (|z^n| > Σ|a_j||z|^{n−j} on |z| ≥ 1, so no root there) and costs no division.
  double sum = 0;
  for (int j = 0; j < n; ++j) sum += std::abs(p[j]);
  if (sum < 1) return true;
  // a^(n) = p; step down a^(i−1)_j = (a^(i)_j − k_i a^(i)_{i−j}) / (1 − k_i²), k_i = a^(i)_i.
  for (int j = 0; j < n; ++j) work[j] = p[j];  // work[j] = a_{j+1}
  for (int i = n; i >= 1; --i) {
    const double k = work[i - 1];
    if (!(std::abs(k) < 1)) return false;
    const double scale = 1 / (1 - k * k);
    for (int j = 1; j <= i / 2; ++j) {
      const double lo = work[j - 1], hi = work[i - j - 1];
      work[j - 1] = (lo - k * hi) * scale;
      work[i - j - 1] = (hi - k * lo) * scale;
    }
  }
  return true;
}

double LargestRootModulus(const double* p, int n) {
  while (n > 0 && p[n - 1] == 0) --n;  // roots at 0
  if (n == 0) return 0;
  double max_abs = 0;
  for (int j = 0; j < n; ++j) {
    if (!std::isfinite(p[j])) return std::numeric_limits<double>::quiet_NaN();
    max_abs = std::max(max_abs, std::abs(p[j]));
  }
  // The roots of 1 + Σ p_j r^−j q^−j are those of p divided by r: R is the least r for which MonicStable passes
  // them. Bisected (geometric midpoints) between |p_n|^(1/n), the geometric mean of the roots' moduli (not above
  // R), and Cauchy's bound 1 + max|p_j| (above R).
  std::vector<double> scaled(static_cast<std::size_t>(n)), work(static_cast<std::size_t>(n));
  double lo = std::pow(std::abs(p[n - 1]), 1.0 / n), hi = 1 + max_abs;
  for (int step = 0; step < 200 && hi > lo * (1 + 0x1p-50); ++step) {
    const double r = std::sqrt(lo) * std::sqrt(hi);
    double s = 1;
    for (int j = 0; j < n; ++j) scaled[static_cast<std::size_t>(j)] = p[j] * (s /= r);
    (MonicStable(scaled.data(), n, work.data()) ? hi : lo) = r;
  }
  return hi;
}

}  // namespace ident::models
