// Error-free transformations and double-double accumulation for the MAP smoother's duality certificate
// (internal to ident/smoothing/): Knuth's TwoSum and the FMA TwoProduct (Ogita, Rump & Oishi, "Accurate sum
// and dot product", SIAM J. Sci. Comput. 26 (2005), sec. 2), and Neumaier's compensated sum (Higham,
// "Accuracy and Stability of Numerical Algorithms", 2nd ed., sec. 4.3).
#pragma once

#include <cmath>

namespace ident::internal {

// An unevaluated sum hi + lo with |lo| <= ulp(hi)/2 after Normalize.
struct DoubleDouble {
  double hi = 0, lo = 0;

  // += a exactly up to the final renormalisation (TwoSum).
  void Add(double a) {
    const double s = hi + a, bb = s - hi;
    lo += (hi - (s - bb)) + (a - bb);
    hi = s;
  }
  // += a * b with the product's rounding error kept (TwoProduct by FMA).
  void AddProduct(double a, double b) {
    const double p = a * b;
    lo += std::fma(a, b, -p);
    Add(p);
  }
  // += a * (b.hi + b.lo): the product with b.lo in plain double (its error is O(eps^2 |a b|)).
  void AddProduct(double a, const DoubleDouble& b) {
    AddProduct(a, b.hi);
    lo += a * b.lo;
  }
  void Normalize() {
    const double s = hi + lo;
    lo = lo - (s - hi);
    hi = s;
  }
  double value() const { return hi + lo; }
};

// Neumaier's compensated sum: the result's error is at most 2 eps |sum| + O(N eps^2) sum |a_i|.
class CompensatedSum {
 public:
  void Add(double a) {
    const double t = sum_ + a;
    compensation_ += std::abs(sum_) >= std::abs(a) ? (sum_ - t) + a : (a - t) + sum_;
    sum_ = t;
  }
  double value() const { return std::isfinite(sum_) ? sum_ + compensation_ : sum_; }

 private:
  double sum_ = 0, compensation_ = 0;
};

}  // namespace ident::internal
