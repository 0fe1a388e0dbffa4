// ARMAX, output-error (OE) and Box–Jenkins (BJ) model structures: the polynomial models whose noise
// model or input dynamics make the predictor depend on the model's own past residuals or simulated outputs
// (Ljung, System Identification, 2nd ed., §4.2, eqs. (4.33)–(4.37)).
//
//   ARMAX  A(q) y(t) = Σ_i B_i(q) u_i(t−nk_i) + C(q) e(t)           nd = nf = 0, nc ≥ 1
//   OE     y(t) = B(q)/F(q) u(t−nk) + e(t)                          na = nc = nd = 0, nf ≥ 1, one input
//   BJ     y(t) = B(q)/F(q) u(t−nk) + C(q)/D(q) e(t)                na = 0, nf ≥ 1, nc + nd ≥ 1, one input
//   A = 1 + a1 q⁻¹ + … + a_na q⁻ⁿᵃ, B_i = b_i1 + b_i2 q⁻¹ + …, C = 1 + c1 q⁻¹ + …, D = 1 + d1 q⁻¹ + …,
//   F = 1 + f1 q⁻¹ + …
//
// θ = [a1 … a_na, b-blocks as in models/arx.h, c1 … c_nc, d1 … d_nd, f1 … f_nf] and the pseudo-linear
// regressor (Ljung §10.3, eq. (10.52); Ljung & Söderström 1983, §3.7) in the same order
//   φ(t) = [−y(t−1) … −y(t−na), u_i(t−nk_i) …, ε(t−1) … ε(t−nc), −v(t−1) … −v(t−nd), −w(t−1) … −w(t−nf)]
// with w = B/F u the noise-free output, v = A y − w the noise, ε = y − θ'φ the residual (D v = C ε), so
// that y(t) = θ'φ(t) + e(t) at the true θ (models/pseudo_linear_regressor.h forms φ).
//
// Example: PolynomialStructure::Armax(2, {2}, 2, {1}).ToString() == "ARMAX(2,2,2,1)".
#pragma once

#include <string>
#include <vector>

#include "models/arx.h"

namespace ident::models {

class PolynomialStructure {
 public:
  // Throws InvalidArgument (naming the order) for negative orders, a combination that is none of
  // ARMAX/OE/BJ, F with several inputs, or the limits of ArxStructure.
  PolynomialStructure(int na, std::vector<int> nb, std::vector<int> nk, int nc, int nd, int nf);
  static PolynomialStructure Armax(int na, std::vector<int> nb, int nc, std::vector<int> nk) {
    return {na, std::move(nb), std::move(nk), nc, 0, 0};
  }
  static PolynomialStructure OutputError(int nb, int nf, int nk) { return {0, {nb}, {nk}, 0, 0, nf}; }
  static PolynomialStructure BoxJenkins(int nb, int nc, int nd, int nf, int nk) { return {0, {nb}, {nk}, nc, nd, nf}; }

  // The y/u part: ARX(na, nb, nk) with na = 0 for OE and BJ.
  const ArxStructure& arx() const { return arx_; }
  int na() const { return arx_.na(); }
  int nc() const { return nc_; }
  int nd() const { return nd_; }
  int nf() const { return nf_; }
  int num_inputs() const { return arx_.num_inputs(); }
  int num_parameters() const { return arx_.num_parameters() + nc_ + nd_ + nf_; }
  // t0 = max(ARX t0, nc, nd, nf): the first sample whose regressor reaches no sample before the segment.
  int first_regression_index() const { return t0_; }
  // Offsets of the c, d and f blocks in θ.
  int c_offset() const { return arx_.num_parameters(); }
  int d_offset() const { return c_offset() + nc_; }
  int f_offset() const { return d_offset() + nd_; }
  // "ARMAX(na,nb,nc,nk)", "OE(nb,nf,nk)", "BJ(nb,nc,nd,nf,nk)" (the order of MATLAB's armax/oe/bj);
  // several inputs as "ARMAX(2,[2,2],1,[1,1])".
  std::string ToString() const;
  // a1…, b1… (b1_1… for several inputs), c1…, d1…, f1….
  std::vector<std::string> ParameterNames() const;

 private:
  ArxStructure arx_;
  int nc_, nd_, nf_;
  int t0_ = 0;
};

// True if the monic polynomial 1 + p1 q⁻¹ + … + p_n q⁻ⁿ has every root strictly inside the unit circle
// (the Schur–Cohn step-down test: every reflection coefficient |k_i| < 1; Söderström & Stoica 1989,
// complement C5.1). `work` holds at least n doubles; no allocation. O(n²).
bool MonicStable(const double* p, int n, double* work);

// The largest modulus of the roots of 1 + p1 q⁻¹ + … + p_n q⁻ⁿ (the eigenvalues of its companion matrix), to a
// relative 2⁻⁵⁰, by bisection with MonicStable; 0 for n = 0, NaN if a coefficient is not finite. Allocates;
// O(n²) per bisection step; for reports, not for the recursion.
double LargestRootModulus(const double* p, int n);

}  // namespace ident::models
