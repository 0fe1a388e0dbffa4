// The floor of what an LD-form RLS update costs: a minimal fixed-size recursive least squares with
// exponential forgetting on the L'DL factor of the unnormalised extended information
//
//   Λ(t) = λΛ(t−1) + h h',  h = [y; z],  Λ = L'DL  (L unit lower triangular, index 0 = y),
//
// updated by the Agee–Turner / Bierman rank-one sweep (Gill–Golub–Murray–Saunders 1974, method C1; the
// loop of ident::LdFactor::RankOneUpdate with d ← λd folded in) [spec §6, §7b], and Θ̂ = L_z⁻¹l_zy by
// forward substitution on demand. ident's RLS keeps the normalised V = Λ/ν: the same L, so the same Θ̂.
// No input check, no guard, no bookkeeping: ~2(ρ+1)² flops per update. bench/ld_kernel_benchmark.cc
// times ident's fixed-size RLS against it; tests/regression/ld_kernel_test.cc checks its Θ̂.
//
//   ident::bench::LdKernel<4> k(/*lambda=*/0.99, d0);   // d0: diagonal of the prior information ν0·V0
//   k.Update(y, z);                                      // z: 4 contiguous doubles
//   std::array<double, 4> theta = k.Parameters();
#pragma once

#include <array>

namespace ident::bench {

template <int Rho>
class LdKernel {
  static constexpr int kM = Rho + 1;

 public:
  // L = I, d = d0 (the factor of a diagonal prior information, all entries > 0).
  LdKernel(double lambda, const std::array<double, kM>& d0) : lambda_(lambda), d_(d0) {
    for (int j = 0; j < kM; ++j)
      for (int i = 0; i < kM; ++i) L_[j][i] = i == j ? 1.0 : 0.0;
  }

  // Λ ← λΛ + hh'. Sweep from the last index, c = 1 [spec §6]:
  //   d'_j = λd_j,  dn = d'_j + c a_j²,  b = c a_j/dn,  c ← c d'_j/dn,  d_j = dn,
  //   for i < j:  a_i −= a_j L[j,i],  L[j,i] += b a_i   (updated a_i).
  void Update(double y, const double* z) noexcept {
    double a[kM];
    a[0] = y;
    for (int i = 1; i < kM; ++i) a[i] = z[i - 1];
    double c = 1;
    for (int j = kM - 1; j >= 0; --j) {
      const double aj = a[j], dj = lambda_ * d_[j];
      const double dn = dj + c * aj * aj;
      const double b = c * aj / dn;
      c = c * dj / dn;
      d_[j] = dn;
      double* row = L_[j].data();
      for (int i = 0; i < j; ++i) {
        a[i] -= aj * row[i];
        row[i] += b * a[i];
      }
    }
  }

  // Θ̂_i = L[i+1, 0] − Σ_{k<i} L[i+1, k+1] Θ̂_k  (L_z Θ̂ = l_zy).
  std::array<double, Rho> Parameters() const noexcept {
    std::array<double, Rho> theta;
    for (int i = 0; i < Rho; ++i) {
      double s = L_[i + 1][0];
      for (int k = 0; k < i; ++k) s -= L_[i + 1][k + 1] * theta[k];
      theta[i] = s;
    }
    return theta;
  }
  // d_0 = the discounted residual sum of squares (Λ's D_y).
  double ResidualSum() const noexcept { return d_[0]; }

 private:
  double lambda_;
  std::array<double, kM> d_;
  std::array<std::array<double, kM>, kM> L_;
};

}  // namespace ident::bench
