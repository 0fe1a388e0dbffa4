// The RST control law of a (self-tuning) regulator, with its signal history.
//
//   R(q⁻¹) u(t) = T(q⁻¹) r(t) − S(q⁻¹) y(t),  R(0) = 1, i.e.
//   u(t) = Σ_i T_i r(t−i) − Σ_i S_i y(t−i) − Σ_{i≥1} R_i u(t−i),   then clamped to [−u_max, u_max].
//   The clamped (applied) u enters the history, so the integrator in R cannot wind up beyond the
//   limit (Åström & Wittenmark, Adaptive Control, §11.2: anti-windup for RST controllers by feeding
//   back the actual plant input).
// Polynomials may change between samples (a self-tuning regulator redesigns every sample); their
// sizes are fixed at construction. Control() is noexcept and allocation-free; ~2(deg R + deg S +
// deg T) flops.
//
// Example:
//   ident::control::RstController law(/*deg_r=*/2, /*deg_s=*/2, /*deg_t=*/1, /*u_max=*/10);
//   law.set_polynomials(design.R(), design.S(), design.T());
//   double u = law.Control(r, y);
#pragma once

#include <algorithm>
#include <limits>

#include <Eigen/Core>

#include "common/error.h"

namespace ident::control {

class RstController {
 public:
  // Throws InvalidArgument if a degree is negative or u_max is not positive.
  RstController(int deg_r, int deg_s, int deg_t, double u_max = std::numeric_limits<double>::infinity())
      : u_max_(u_max) {
    IDENT_REQUIRE(deg_r >= 0 && deg_s >= 0 && deg_t >= 0, "degrees (R, S, T) = ({}, {}, {}); need >= 0", deg_r, deg_s,
                  deg_t);
    IDENT_REQUIRE(u_max > 0, "u_max = {}; need u_max > 0", u_max);
    R_ = Eigen::VectorXd::Zero(deg_r + 1);
    R_(0) = 1;
    S_ = Eigen::VectorXd::Zero(deg_s + 1);
    T_ = Eigen::VectorXd::Zero(deg_t + 1);
    u_past_ = Eigen::VectorXd::Zero(deg_r + 1);
    y_past_ = Eigen::VectorXd::Zero(deg_s + 1);
    r_past_ = Eigen::VectorXd::Zero(deg_t + 1);
  }

  // Throws InvalidArgument if a size differs from construction or R(0) != 1.
  void set_polynomials(const Eigen::Ref<const Eigen::VectorXd>& R, const Eigen::Ref<const Eigen::VectorXd>& S,
                       const Eigen::Ref<const Eigen::VectorXd>& T) {
    IDENT_REQUIRE(R.size() == R_.size() && S.size() == S_.size() && T.size() == T_.size(),
                  "polynomial sizes (R, S, T) = ({}, {}, {}); need ({}, {}, {})", R.size(), S.size(), T.size(),
                  R_.size(), S_.size(), T_.size());
    IDENT_REQUIRE(R(0) == 1.0, "R(0) = {}; need a monic R", R(0));
    R_ = R;
    S_ = S;
    T_ = T;
  }

  // u(t) from r(t) and the measured y(t); stores all three for the next sample.
  double Control(double r, double y) noexcept {
    Shift(r_past_, r);
    Shift(y_past_, y);
    double u = T_.dot(r_past_) - S_.dot(y_past_);
    for (Eigen::Index i = 1; i < R_.size(); ++i) u -= R_(i) * u_past_(i - 1);
    u = std::clamp(u, -u_max_, u_max_);
    Shift(u_past_, u);
    return u;
  }

  void Reset() noexcept {
    u_past_.setZero();
    y_past_.setZero();
    r_past_.setZero();
  }

 private:
  // h(0) = newest.
  static void Shift(Eigen::VectorXd& h, double v) noexcept {
    for (Eigen::Index i = h.size() - 1; i > 0; --i) h(i) = h(i - 1);
    h(0) = v;
  }

  double u_max_;
  Eigen::VectorXd R_, S_, T_;
  Eigen::VectorXd u_past_, y_past_, r_past_;
};

}  // namespace ident::control
