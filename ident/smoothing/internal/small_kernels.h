// Matrix-vector kernels for the small blocks of the MAP smoother's interior point (internal to
// ident/smoothing/): y += αAx and y += αA'x on column-major arrays, as plain loops that unroll when the
// sizes are fixed at compile time.
#pragma once

namespace ident::internal {

// y += alpha A x (A r x c column-major, plain loops: several times faster than Eigen's dynamic-size
// kernels for the tiny blocks here). kR, kC > 0 fix the sizes at compile time (the loops unroll).
template <int kR = 0, int kC = 0>
[[gnu::always_inline]] inline void AddMatVec(const double* A, int r_runtime, int c_runtime, const double* x, double* y,
                                             double alpha) {
  const int r = kR > 0 ? kR : r_runtime, c = kC > 0 ? kC : c_runtime;
  for (int j = 0; j < c; ++j) {
    const double xj = alpha * x[j];
    for (int i = 0; i < r; ++i) y[i] += A[i + j * r] * xj;
  }
}
// y += alpha A' x.
template <int kR = 0, int kC = 0>
[[gnu::always_inline]] inline void AddMatTVec(const double* A, int r_runtime, int c_runtime, const double* x, double* y,
                                              double alpha) {
  const int r = kR > 0 ? kR : r_runtime, c = kC > 0 ? kC : c_runtime;
  for (int j = 0; j < c; ++j) {
    double s = 0;
    for (int i = 0; i < r; ++i) s += A[i + j * r] * x[i];
    y[j] += alpha * s;
  }
}

}  // namespace ident::internal
