// Matrix-vector kernels for the small blocks of the MAP smoother's interior point (internal to
// ident/smoothing/): y += αAx and y += αA'x on column-major arrays, as plain loops that unroll when the
// sizes are fixed at compile time, and the in-place inverse of a small symmetric positive definite block.
#pragma once

#include <cmath>

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

// In-place inverse of a symmetric positive definite kN x kN matrix (column-major); false if a pivot is not
// positive. n = 1, 2 in closed form (one reciprocal), Gauss-Jordan without pivoting beyond.
template <int kN>
[[gnu::always_inline]] inline bool InvertSpd(double* A) {
  if constexpr (kN == 1) {
    if (!(A[0] > 0) || !std::isfinite(A[0])) return false;
    A[0] = 1.0 / A[0];
    return true;
  } else if constexpr (kN == 2) {
    const double a = A[0], b = A[1], d = A[3];
    const double det = a * d - b * b;
    if (!(a > 0) || !(det > 0) || !std::isfinite(det)) return false;
    const double idet = 1.0 / det;
    A[0] = d * idet;
    A[1] = A[2] = -b * idet;
    A[3] = a * idet;
    return true;
  } else {
    for (int k = 0; k < kN; ++k) {
      const double pivot = A[k + k * kN];
      if (!(pivot > 0) || !std::isfinite(pivot)) return false;
      const double ip = 1.0 / pivot;
      A[k + k * kN] = 1.0;
      for (int j = 0; j < kN; ++j) A[k + j * kN] *= ip;
      for (int i = 0; i < kN; ++i) {
        if (i == k) continue;
        const double f = A[i + k * kN];
        A[i + k * kN] = 0.0;
        for (int j = 0; j < kN; ++j) A[i + j * kN] -= f * A[k + j * kN];
      }
    }
    return true;
  }
}

}  // namespace ident::internal
