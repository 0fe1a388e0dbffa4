// Property of LD-form recursive least squares (ident::RecursiveLeastSquares) fed arbitrary doubles.
// Input: 1 byte ρ (1..6), 1 byte forgetting choice, 1 byte flags (bit 0 stabilised forgetting,
// bit 1 informative prior), then (y, z_1..z_ρ) as raw doubles, one sample after another.
// Holds if, after every step:
//   updated  -> ν > 0, every d_i a finite normal number > 0, L and Θ̂ finite;
//   rejected -> the state (ν, L, d) is bit-for-bit unchanged.
// Update() is noexcept: a throw would terminate the process, which libFuzzer reports.
// With flags bit 2 (and forgetting 1, 0.999 or 0.99, not stabilised, the informative prior) the samples
// are tame instead (each number a signed byte / 16, at most 300 samples) and the LD form is checked
// against the plain covariance-form oracle (tests/support/dense_rls.h) after every step:
//   |θ_LD − θ_dense| ≤ 1e-6·(1 + |θ|) and ν equal to 1e-12 relative.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>

#include <Eigen/Core>

#include "fuzz/fuzz_util.h"
#include "ident/regression/rls.h"
#include "tests/support/dense_rls.h"

namespace ident::fuzz {

inline std::string RlsProperty(const std::uint8_t* data, std::size_t size) {
  ByteReader in(data, size);
  const int rho = 1 + in.Byte() % 6;
  static constexpr double kFactors[] = {1.0, 0.999, 0.99, 0.9, 0.5, 1e-3};
  RlsOptions options;
  options.forgetting.factor = kFactors[in.Byte() % 6];
  const std::uint8_t flags = in.Byte();
  options.forgetting.stabilised = (flags & 1) != 0;
  if (flags & 2) options.prior = RegressionPrior::Diagonal(rho, 1.0 + rho, 1.0, 1e-3);
  RecursiveLeastSquares rls(rho, options);
  if ((flags & 4) && options.forgetting.factor >= 0.99 && !options.forgetting.stabilised && options.prior) {
    DenseRls dense(*options.prior, options.forgetting.factor);
    Eigen::VectorXd z(rho);
    for (int step = 0; step < 300 && in.remaining() >= static_cast<std::size_t>(rho + 1); ++step) {
      const double y = static_cast<std::int8_t>(in.Byte()) / 16.0;
      for (int i = 0; i < rho; ++i) z(i) = static_cast<std::int8_t>(in.Byte()) / 16.0;
      if (!rls.Update(y, z).updated()) return "a tame sample is accepted";
      dense.Update(y, z);
      const Eigen::VectorXd& a = rls.parameters();
      const Eigen::VectorXd& b = dense.parameters();
      for (int i = 0; i < rho; ++i)
        if (!(std::abs(a(i) - b(i)) <= 1e-6 * (1 + std::abs(b(i))))) return "the LD form equals the dense oracle";
      if (!(std::abs(rls.nu() - dense.nu()) <= 1e-12 * dense.nu())) return "nu equals the dense oracle's";
    }
    return {};
  }
  Eigen::VectorXd z(rho), d0;
  Eigen::MatrixXd L0;
  while (in.remaining() >= 8 * static_cast<std::size_t>(rho + 1)) {
    const double y = in.Double();
    for (int i = 0; i < rho; ++i) z(i) = in.Double();
    const auto& s = rls.statistics();
    d0 = s.factor().d();
    L0 = s.factor().L();
    const double nu0 = s.nu();
    const StepReport report = rls.Update(y, z);
    const auto& d = s.factor().d();
    if (report.updated()) {
      if (!(std::isfinite(s.nu()) && s.nu() > 0)) return "nu stays positive and finite";
      if (!(d.allFinite() && d.minCoeff() >= std::numeric_limits<double>::min())) return "D stays positive (normal)";
      if (!s.factor().L().allFinite()) return "L stays finite";
      if (!rls.parameters().allFinite()) return "parameters stay finite";
    } else if (!(s.nu() == nu0 && d == d0 && s.factor().L() == L0)) {
      return "a rejected step leaves the state unchanged";
    }
  }
  return {};
}

}  // namespace ident::fuzz
