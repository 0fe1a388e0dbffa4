// Matrix-vector kernels for the small blocks of the MAP smoother's interior point (internal to
// ident/smoothing/): y += αAx and y += αA'x on column-major arrays, as plain loops that unroll when the
// sizes are fixed at compile time.
#pragma once

namespace ident::internal {

// y += alpha A x (A r x c column-major, plain loops: for the tiny blocks here Eigen's dynamic-size kernels
// spend more on their set-up than on the arithmetic). kR, kC > 0 fix the sizes at compile time (the loops unroll).
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

// The Newton blocks of a process term w_t = x_t − F x_{t−1} with weight W (n x n): WF = W F (scratch, n x n),
// E_t −= W F, D_{t−1} += F'W F. All n x n column-major.
inline void AddProcessCoupling(const double* W, const double* F, int n, double* WF, double* Et, double* Dp) {
  for (int b = 0; b < n; ++b)
    for (int a = 0; a < n; ++a) {
      double wf = 0;
      for (int c = 0; c < n; ++c) wf += W[a + c * n] * F[c + b * n];
      WF[a + b * n] = wf;
      Et[a + b * n] -= wf;
    }
  for (int b = 0; b < n; ++b)
    for (int a = 0; a < n; ++a) {
      double s = 0;
      for (int c = 0; c < n; ++c) s += F[c + a * n] * WF[c + b * n];
      Dp[a + b * n] += s;
    }
}
// The Newton block of a measurement term r_t = z_t − H x_t with weight W (nz x nz): WH = W H (scratch,
// nz x n), D_t += H'W H (n x n).
inline void AddMeasurementBlock(const double* W, const double* H, int n, int nz, double* WH, double* Dt) {
  for (int b = 0; b < n; ++b)
    for (int a = 0; a < nz; ++a) {
      double wh = 0;
      for (int c = 0; c < nz; ++c) wh += W[a + c * nz] * H[c + b * nz];
      WH[a + b * nz] = wh;
    }
  for (int b = 0; b < n; ++b)
    for (int a = 0; a < n; ++a) {
      double s = 0;
      for (int c = 0; c < nz; ++c) s += H[c + a * nz] * WH[c + b * nz];
      Dt[a + b * n] += s;
    }
}

}  // namespace ident::internal
