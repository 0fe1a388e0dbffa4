// Property of the Kárný–Hangos Student-t / Cauchy regression (ident::StudentRegression) fed
// arbitrary doubles. Input: 1 byte ρ (1..6), 1 byte k ∈ {1 (Cauchy), 3, 0.5, 30}, 1 byte forgetting
// choice, 1 byte flags (bit 0 stabilised, bit 1 δ = 0, bit 2 informative prior), then (y, z_1..z_ρ)
// raw doubles per step. Options the constructor refuses (InvalidArgument, e.g. inadmissible
// forgetting) end the run: refusing them is the specified answer.
// Holds if, after every step, ν > 0, every d_i a positive normal number, L and Θ̂ finite, β ∈ (0, 1)
// for an updated step; a step not taken (rejected as invalid or as a numerical failure) leaves the
// state bit-for-bit unchanged. Update() is noexcept: a throw would terminate the process.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>

#include <Eigen/Core>

#include "common/error.h"
#include "fuzz/fuzz_util.h"
#include "ident/regression/student_regression.h"

namespace ident::fuzz {

inline std::string StudentProperty(const std::uint8_t* data, std::size_t size) {
  ByteReader in(data, size);
  const int rho = 1 + in.Byte() % 6;
  static constexpr double kDofs[] = {1.0, 3.0, 0.5, 30.0};
  static constexpr double kFactors[] = {1.0, 0.999, 0.99, 0.9, 0.5, 1e-3};
  StudentRegressionOptions options;
  options.dof = kDofs[in.Byte() % 4];
  options.forgetting.factor = kFactors[in.Byte() % 6];
  const std::uint8_t flags = in.Byte();
  options.forgetting.stabilised = (flags & 1) != 0;
  options.delta = (flags & 2) ? 0 : 1;
  if (flags & 4) options.prior = RegressionPrior::Diagonal(rho, rho + 4.0, 1.0, 1e-3);
  std::optional<StudentRegression> est;
  try {
    est.emplace(rho, options);
  } catch (const InvalidArgument&) {
    return {};
  }
  Eigen::VectorXd z(rho), d0;
  Eigen::MatrixXd L0;
  while (in.remaining() >= 8 * static_cast<std::size_t>(rho + 1)) {
    const double y = in.Double();
    for (int i = 0; i < rho; ++i) z(i) = in.Double();
    const auto& s = est->statistics();
    d0 = s.factor().d();
    L0 = s.factor().L();
    const double nu0 = s.nu();
    const StepReport report = est->Update(y, z);
    const auto& d = s.factor().d();
    if (!report.updated()) {
      if (!(s.nu() == nu0 && d == d0 && s.factor().L() == L0)) return "a step not taken leaves the state unchanged";
      continue;
    }
    if (report.updated() && !(report.weight > 0 && report.weight < 1)) return "beta in (0, 1)";
    if (!(std::isfinite(s.nu()) && s.nu() > 0)) return "nu stays positive and finite";
    if (!(d.allFinite() && d.minCoeff() >= std::numeric_limits<double>::min())) return "D stays positive (normal)";
    if (!s.factor().L().allFinite()) return "L stays finite";
    if (!est->parameters().allFinite()) return "parameters stay finite";
  }
  return {};
}

}  // namespace ident::fuzz
