// The program both package consumers build: fits y = a + b x by recursive least squares (fixed size
// and dynamic size) and checks the estimate against the closed-form simple-regression solution
//   b = Σ(x−x̄)(y−ȳ) / Σ(x−x̄)²,   a = ȳ − b x̄.
// Exit code 0 if both agree to 1e-8, 1 otherwise.
#include <algorithm>
#include <cmath>
#include <cstdio>

#include <Eigen/Core>

#include "common/error.h"
#include "ident/regression/rls.h"

int main() {
  constexpr int kSamples = 20;
  double x[kSamples], y[kSamples];
  for (int t = 0; t < kSamples; ++t) {
    x[t] = 0.5 * t - 3;
    y[t] = 1.5 - 0.75 * x[t] + ((t * 7) % 5 - 2) * 0.1;  // deterministic "noise"
  }
  double xm = 0, ym = 0;
  for (int t = 0; t < kSamples; ++t) xm += x[t] / kSamples, ym += y[t] / kSamples;
  double sxy = 0, sxx = 0;
  for (int t = 0; t < kSamples; ++t) sxy += (x[t] - xm) * (y[t] - ym), sxx += (x[t] - xm) * (x[t] - xm);
  const double b = sxy / sxx, a = ym - b * xm;

  ident::BasicRecursiveLeastSquares<2> fixed(2);
  ident::RecursiveLeastSquares dynamic(2);
  for (int t = 0; t < kSamples; ++t) {
    const Eigen::Vector2d z(1.0, x[t]);
    if (!fixed.Update(y[t], z).updated() || !dynamic.Update(y[t], z).updated()) return 1;
  }
  const double err = std::max({std::abs(fixed.parameters()(0) - a), std::abs(fixed.parameters()(1) - b),
                               std::abs(dynamic.parameters()(0) - a), std::abs(dynamic.parameters()(1) - b)});
  std::printf("closed form a = %.12f b = %.12f; RLS a = %.12f b = %.12f; max error %.3g\n", a, b, fixed.parameters()(0),
              fixed.parameters()(1), err);
  bool threw = false;  // the error type is usable from the package too
  try {
    ident::RecursiveLeastSquares bad(0);
  } catch (const ident::InvalidArgument&) {
    threw = true;
  }
  return err < 1e-8 && threw ? 0 : 1;
}
