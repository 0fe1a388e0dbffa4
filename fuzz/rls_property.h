// Property of LD-form recursive least squares (ident::RecursiveLeastSquares) fed arbitrary doubles.
// Input: 1 byte ρ (1..6), 1 byte forgetting choice, 1 byte flags (bit 0 stabilised forgetting,
// bit 1 informative prior), then (y, z_1..z_ρ) as raw doubles, one sample after another.
// Holds if, after every step:
//   updated  -> ν > 0, every d_i a finite normal number > 0, L and Θ̂ finite;
//   rejected -> the state (ν, L, d) is bit-for-bit unchanged.
// Update() is noexcept: a throw would terminate the process, which libFuzzer reports.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>

#include <Eigen/Core>

#include "fuzz/fuzz_util.h"
#include "ident/rls.h"

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
