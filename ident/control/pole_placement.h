// Pole-placement design of an RST controller from an estimated ARX model — the design step of an
// indirect self-tuning regulator. Polynomials are in the backward shift q⁻¹, stored as ascending
// coefficient vectors: p = [p0, p1, …] means p0 + p1 q⁻¹ + ….
//
//   Plant (ARX, one input, delay nk ≥ 1):
//           A(q⁻¹) y(t) = B(q⁻¹) u(t) + e(t),  A = 1 + a1 q⁻¹ + … + a_na q⁻ⁿᵃ,
//           B = q^{−nk} (b1 + b2 q⁻¹ + … + b_nb q^{−nb+1})   (θ = [a; b] as in models/arx.h)
//   Law:    R(q⁻¹) u(t) = T(q⁻¹) r(t) − S(q⁻¹) y(t)
//   Design: A R + B S = Ac = Am Ao          (the Diophantine equation; closed-loop poles = zeros of Ac)
//           integral action: R = (1 − q⁻¹) R̄,  so  A(1 − q⁻¹) R̄ + B S = Ac
//           minimum degrees: deg R̄ = deg B − 1, deg S = deg A' − 1 (A' = A or A(1 − q⁻¹)), R(0) = 1;
//           needs deg Ac ≤ deg A' + deg B − 1
//           T = t0 Ao,  t0 = Am(1)/B(1)      (static gain r → y equal to 1)
//   Åström & Wittenmark, Adaptive Control (2nd ed., 1995), §3.2, minimum-degree pole placement
//   without cancellation of process zeros (B⁺ = 1).
//   Solve:  the Sylvester system M x = Ac, M (N x N, N = deg A' + deg B) with column j < deg B the
//           coefficients of q^{−j} A' and column deg B + j those of q^{−j} B; x = [R̄; S].
//           Partial-pivoting LU; a near-singular M (A' and B with a common factor: the model is not
//           controllable) is reported, not thrown.
//
// Cost: O(N³) per Design() (N = 5 for a second-order plant with integral action); no allocation
// after construction.
//
// Example (second-order plant, closed-loop poles at 0.6 (double), observer pole 0.3, integrator):
//   ident::control::PolePlacementOptions o;
//   o.am = Eigen::Vector3d(1, -1.2, 0.36);
//   o.ao = Eigen::Vector2d(1, -0.3);
//   ident::control::PolePlacement design(/*na=*/2, /*nb=*/2, /*nk=*/1, o);
//   if (design.Design(theta.head(2), theta.tail(2)) == ident::control::DesignStatus::kOk)
//     controller.set_polynomials(design.R(), design.S(), design.T());
#pragma once

#include <string>

#include <Eigen/Core>
#include <Eigen/LU>

namespace ident::control {

struct PolePlacementOptions {
  Eigen::VectorXd am = Eigen::Vector3d(1, -1.2, 0.36);  // desired (model) poles Am, Am(0) = 1
  Eigen::VectorXd ao = Eigen::VectorXd::Ones(1);        // observer polynomial Ao, Ao(0) = 1
  bool integral_action = true;                          // R = (1 − q⁻¹) R̄: zero steady-state error

  // "" if valid for the given structure, else one line naming the option.
  std::string Validate(int na, int nb, int nk) const;
};

enum class DesignStatus {
  kOk,               // R, S, T updated
  kInvalidModel,     // a or b has the wrong size or a non-finite entry; R, S, T unchanged
  kNotControllable,  // A' and B (nearly) share a factor, or B(1) ≈ 0; R, S, T unchanged
};

class PolePlacement {
 public:
  // Throws InvalidArgument naming the option if na < 0, nb < 1, nk < 1 or the options are invalid.
  PolePlacement(int na, int nb, int nk, const PolePlacementOptions& options = {});

  // Solves the Diophantine equation for A = [1, a], B = q^{−nk}[b]. noexcept, allocation-free.
  DesignStatus Design(const Eigen::Ref<const Eigen::VectorXd>& a, const Eigen::Ref<const Eigen::VectorXd>& b) noexcept;

  // The last successful design (R(0) = 1). Before the first: R = 1, S = 0, T = 0 (u = 0).
  const Eigen::VectorXd& R() const { return R_; }
  const Eigen::VectorXd& S() const { return S_; }
  const Eigen::VectorXd& T() const { return T_; }
  // Ac = Am Ao, padded with zeros to N coefficients.
  const Eigen::VectorXd& Ac() const { return ac_; }
  int system_size() const { return n_; }

 private:
  int na_, nb_, deg_a_, deg_b_, n_;  // deg_b_ = nk + nb − 1 carries the delay
  PolePlacementOptions options_;
  Eigen::VectorXd ac_, a_full_, b_full_, x_;
  Eigen::MatrixXd M_;
  Eigen::PartialPivLU<Eigen::MatrixXd> lu_;
  Eigen::VectorXd R_, S_, T_;
};

// p ⋅ q (polynomial product = convolution of the coefficient vectors). Allocates; for setup and tests.
Eigen::VectorXd Multiply(const Eigen::VectorXd& p, const Eigen::VectorXd& q);

}  // namespace ident::control
