#include "ident/workflow/student_likelihood.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "common/error.h"

namespace ident::workflow {
namespace {

// log Γ(k/2) − log Γ((k+1)/2) + ½ log(kπ): the per-sample constant of the Student-t_k NLL.
double StudentConstant(double k) {
  return std::lgamma(k / 2) - std::lgamma((k + 1) / 2) + 0.5 * std::log(k * std::numbers::pi);
}

// g(u) = Σ (k+1) r²/(k e^u + r²) − N and g'(u), u = log γ²: NLL's derivative in log γ is −g.
std::pair<double, double> ScaleEquation(const std::vector<double>& r, double k, double u) {
  const double s = std::exp(u);
  double g = -static_cast<double>(r.size()), dg = 0;
  for (const double x : r) {
    const double q = x * x, den = k * s + q;
    g += (k + 1) * q / den;
    dg -= (k + 1) * q * k * s / (den * den);
  }
  return {g, dg};
}

}  // namespace

double StudentNegLogLikelihood(const std::vector<double>& residuals, double k, double scale) {
  const double n = static_cast<double>(residuals.size());
  double sum = 0;
  for (const double x : residuals) sum += std::log1p(x * x / (k * scale * scale));
  return (k + 1) / 2 * sum + n * std::log(scale) + n * StudentConstant(k);
}

StudentProfile ProfileStudentLikelihood(const std::vector<double>& residuals, double k) {
  IDENT_REQUIRE(std::isfinite(k) && k > 0, "Student-t likelihood: need k > 0 (got {})", k);
  IDENT_REQUIRE(!residuals.empty(), "Student-t likelihood: no residuals");
  const double n = static_cast<double>(residuals.size());
  double mean_square = 0;
  long nonzero = 0;
  for (const double x : residuals) {
    mean_square += x * x / n;
    if (x != 0) ++nonzero;
  }
  IDENT_REQUIRE((k + 1) * static_cast<double>(nonzero) > n,
                "Student-t likelihood: {} of {} residuals are exactly zero; the scale has no finite optimum",
                residuals.size() - nonzero, residuals.size());
  // g decreases in u from (k+1)·#nonzero − N > 0 (u → −∞) to −N; g(log((k+1)/k · mean r²)) ≤ 0.
  double hi = std::log((k + 1) / k * mean_square), lo = hi - 1;
  while (ScaleEquation(residuals, k, lo).first <= 0) lo -= 2 * (hi - lo);
  double u = std::log(mean_square);
  if (!(u > lo && u < hi)) u = 0.5 * (lo + hi);
  for (int iteration = 0; iteration < 200; ++iteration) {
    const auto [g, dg] = ScaleEquation(residuals, k, u);
    if (g == 0) break;
    (g > 0 ? lo : hi) = u;
    double next = dg < 0 ? u - g / dg : 0.5 * (lo + hi);
    if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);  // Newton left the bracket: bisect
    if (std::abs(next - u) <= 1e-15 * std::max(1.0, std::abs(u)) || hi - lo <= 1e-15 * std::max(1.0, std::abs(u))) {
      u = next;
      break;
    }
    u = next;
  }
  StudentProfile p;
  p.scale = std::exp(0.5 * u);
  p.nll = StudentNegLogLikelihood(residuals, k, p.scale);
  return p;
}

}  // namespace ident::workflow
