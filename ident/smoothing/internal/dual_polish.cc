#include "ident/smoothing/internal/dual_polish.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "ident/linalg/block_tridiagonal.h"
#include "ident/smoothing/internal/small_kernels.h"

namespace ident::internal {
namespace {

// The end of a polish round: kept if max |rho| fell to `next` (into *rho_max), else v and u are restored.
bool KeepRound(double next, double* rho_max, Eigen::MatrixXd& v, Eigen::MatrixXd& u, const Eigen::MatrixXd& v_prev,
               const Eigen::MatrixXd& u_prev) {
  if (next < *rho_max) {
    *rho_max = next;
    return true;
  }
  v = v_prev;
  u = u_prev;
  return false;
}

// PolishMapSmootherDual (dual_polish.h) for a state dimension fixed at compile time: the same rounds on n x n
// blocks held by value, in few passes over the steps. N's block LDL' is kept as P_t = S_t^-1 alone
// (S_t = D_t - E_t P_{t-1} E_t', E_t = -W_t F_{t-1} formed again where it is used). A round is a forward
// substitution and one backward pass that finishes xi_t and, one step behind it, the round's new v, u and
// residual; the new v and u go to a second pair of buffers, swapped in only if max |rho| falls.
template <int kN>
double PolishDualFixed(const MapSmootherProblem& p, const MapSmootherDualIterate& dual, Eigen::MatrixXd* v_out,
                       Eigen::MatrixXd* u_out) {
  using MatN = Eigen::Matrix<double, kN, kN>;
  using VecN = Eigen::Matrix<double, kN, 1>;
  const int T = p.T(), N = T + 1, nz = p.measurement_dim();
  Eigen::MatrixXd& v = *v_out;
  Eigen::MatrixXd& u = *u_out;
  const auto F = [&](int t) { return Eigen::Map<const MatN>(p.Ft(t).data()); };
  const auto W = [&](int t) {
    return Eigen::Map<const MatN>(dual.process_weight.col(ProcessWeightColumn(dual.process_weight, t)).data());
  };
  const auto E = [&](int t) -> MatN { return -W(t) * F(t - 1); };  // t >= 1
  // rho_t = v_t - F_t'v_{t+1} - H_t'u_t of (v, u) (H_t is nz x n, column-major).
  const auto residual = [&](const Eigen::MatrixXd& vv, const Eigen::MatrixXd& uu, int t) {
    VecN r = Eigen::Map<const VecN>(vv.col(t).data());
    if (t < T) r.noalias() -= F(t).transpose() * Eigen::Map<const VecN>(vv.col(t + 1).data());
    const double* H = p.Ht(t).data();
    const double* ut = uu.col(t).data();
    for (int i = 0; i < kN; ++i) {
      double s = 0;
      for (int j = 0; j < nz; ++j) s += H[j + i * nz] * ut[j];
      r(i) -= s;
    }
    return r;
  };
  Eigen::Matrix<double, kN, Eigen::Dynamic> rho(kN, N);
  double rho_max = 0;
  for (int t = 0; t <= T; ++t) {
    rho.col(t) = residual(v, u, t);
    rho_max = std::max(rho_max, rho.col(t).cwiseAbs().maxCoeff());
  }
  if (!(rho_max > 0) || !dual.process_weight.allFinite() || !dual.measurement_weight.allFinite()) return rho_max;
  // N = sum J'WJ: D_t = W_t + F_t'W_{t+1}F_t + H_t'Wg_t H_t, and P_t = S_t^-1; the substitutions are
  // g_t = P_t (b_t - E_t g_{t-1}) and xi_t = g_t - P_t E_{t+1}' xi_{t+1}.
  std::vector<MatN, Eigen::aligned_allocator<MatN>> P(N);
  for (int t = 0; t <= T; ++t) {
    MatN S = W(t);
    if (t < T) S.noalias() += F(t).transpose() * W(t + 1) * F(t);
    const double* H = p.Ht(t).data();
    const double* Wg = dual.measurement_weight.col(t).data();
    for (int a = 0; a < kN; ++a)
      for (int b = 0; b < kN; ++b) {
        double sum = 0;
        for (int i = 0; i < nz; ++i)
          for (int j = 0; j < nz; ++j) sum += H[i + a * nz] * Wg[i + j * nz] * H[j + b * nz];
        S(a, b) += sum;
      }
    if (t > 0) {
      const MatN Et = E(t);
      S.noalias() -= Et * P[t - 1] * Et.transpose();
    }
    if (!InvertSpd<kN>(S.data()) || !S.allFinite()) return rho_max;
    P[t] = S;
  }
  Eigen::Matrix<double, kN, Eigen::Dynamic> g(kN, N);
  Eigen::MatrixXd v_new(kN, N), u_new(nz, N);
  // The round's new v_t = v_t + W_t (xi_t - F_{t-1} xi_{t-1}) and u_t = u_t - Wg_t H_t xi_t (xi_prev =
  // xi_{t-1}, nullptr at t = 0), then rho_t from them (v_new_{t+1} already set); returns max |rho_t|.
  const auto finish_step = [&](int t, const VecN& xi, const VecN* xi_prev) {
    VecN a = xi;
    if (xi_prev) a.noalias() -= F(t - 1) * *xi_prev;
    Eigen::Map<VecN>(v_new.col(t).data()).noalias() = Eigen::Map<const VecN>(v.col(t).data()) + W(t) * a;
    const double* H = p.Ht(t).data();
    const double* Wg = dual.measurement_weight.col(t).data();
    for (int j = 0; j < nz; ++j) {
      double du = 0;
      for (int i = 0; i < nz; ++i) {
        double hx = 0;
        for (int k = 0; k < kN; ++k) hx += H[i + k * nz] * xi(k);
        du += Wg[j + i * nz] * hx;
      }
      u_new(j, t) = u(j, t) - du;
    }
    rho.col(t) = residual(v_new, u_new, t);
    return rho.col(t).cwiseAbs().maxCoeff();
  };
  for (int round = 0; round < 2; ++round) {
    VecN gp = VecN::Zero();
    for (int t = 0; t <= T; ++t) {  // b = -rho
      VecN b = -rho.col(t);
      if (t > 0) b.noalias() -= E(t) * gp;
      gp = P[t] * b;
      g.col(t) = gp;
    }
    double next = 0;
    VecN xi_next = g.col(T);  // xi_{t+1}
    for (int t = T - 1; t >= 0; --t) {
      const VecN xi = g.col(t) - P[t] * (E(t + 1).transpose() * xi_next);
      next = std::max(next, finish_step(t + 1, xi_next, &xi));
      xi_next = xi;
    }
    next = std::max(next, finish_step(0, xi_next, nullptr));
    if (!(next < rho_max)) break;  // the round is not kept: v and u unchanged
    rho_max = next;
    v.swap(v_new);
    u.swap(u_new);
  }
  return rho_max;
}

// PolishMapSmootherDual (dual_polish.h) for any state dimension: N's blocks assembled, then the block
// Cholesky of ident/linalg/block_tridiagonal.h.
double PolishDual(const MapSmootherProblem& p, const MapSmootherDualIterate& dual, Eigen::MatrixXd* v_out,
                  Eigen::MatrixXd* u_out) {
  const int T = p.T(), N = T + 1, n = p.state_dim(), nz = p.measurement_dim();
  Eigen::MatrixXd& v = *v_out;
  Eigen::MatrixXd& u = *u_out;
  auto residual = [&](Eigen::MatrixXd* rho) {  // rho_t = v_t - F_t'v_{t+1} - H_t'u_t
    for (int t = 0; t <= T; ++t) {
      double* rt = rho->col(t).data();
      for (int i = 0; i < n; ++i) rt[i] = v(i, t);
      if (t < T) AddMatTVec(p.Ft(t).data(), n, n, v.col(t + 1).data(), rt, -1.0);
      AddMatTVec(p.Ht(t).data(), nz, n, u.col(t).data(), rt, -1.0);
    }
    return rho->cwiseAbs().maxCoeff();
  };
  Eigen::MatrixXd rho(n, N);
  double rho_max = residual(&rho);
  if (!(rho_max > 0) || !dual.process_weight.allFinite() || !dual.measurement_weight.allFinite()) return rho_max;
  // N = sum J'WJ: D_t = W_t + F_t'W_{t+1}F_t + H_t'Wg_t H_t, E_t = -W_t F_{t-1} (the small-block
  // kernels of the solver's AddNewtonBlocks, small_kernels.h).
  Eigen::MatrixXd D = Eigen::MatrixXd::Zero(n, n * N), E = Eigen::MatrixXd::Zero(n, n * N);
  std::vector<double> WF(static_cast<std::size_t>(n) * n), WH(static_cast<std::size_t>(nz) * n);
  for (int t = 0; t <= T; ++t) {
    const double* W = dual.process_weight.col(ProcessWeightColumn(dual.process_weight, t)).data();
    const double* Wg = dual.measurement_weight.col(t).data();
    double* Dt = D.data() + static_cast<Eigen::Index>(t) * n * n;
    for (int i = 0; i < n * n; ++i) Dt[i] += W[i];
    if (t > 0)
      AddProcessCoupling(W, p.Ft(t - 1).data(), n, WF.data(), E.data() + static_cast<Eigen::Index>(t) * n * n,
                         Dt - n * n);
    AddMeasurementBlock(Wg, p.Ht(t).data(), n, nz, WH.data(), Dt);
  }
  BlockTridiagonalCholesky chol(n, N);
  if (!chol.Factorize(D, E)) return rho_max;
  Eigen::MatrixXd xi(n, N), v_prev, u_prev;
  for (int round = 0; round < 2; ++round) {
    v_prev = v;
    u_prev = u;
    xi = -rho;
    chol.Solve(xi);
    std::vector<double> step(n), gstep(nz);
    double* a = step.data();
    for (int t = 0; t <= T; ++t) {
      for (int i = 0; i < n; ++i) a[i] = xi(i, t);  // (A xi)_t = xi_t - F_{t-1} xi_{t-1}
      if (t > 0) AddMatVec(p.Ft(t - 1).data(), n, n, xi.col(t - 1).data(), a, -1.0);
      AddMatVec(dual.process_weight.col(ProcessWeightColumn(dual.process_weight, t)).data(), n, n, a, v.col(t).data(),
                1.0);
      for (int j = 0; j < nz; ++j) gstep[j] = 0;
      AddMatVec(p.Ht(t).data(), nz, n, xi.col(t).data(), gstep.data(), 1.0);  // H xi
      AddMatVec(dual.measurement_weight.col(t).data(), nz, nz, gstep.data(), u.col(t).data(), -1.0);
    }
    if (!KeepRound(residual(&rho), &rho_max, v, u, v_prev, u_prev)) break;
  }
  return rho_max;
}

}  // namespace

double PolishMapSmootherDual(const MapSmootherProblem& p, const MapSmootherDualIterate& dual, Eigen::MatrixXd* v,
                             Eigen::MatrixXd* u) {
  switch (p.state_dim()) {
    case 1:
      return PolishDualFixed<1>(p, dual, v, u);
    case 2:
      return PolishDualFixed<2>(p, dual, v, u);
    case 3:
      return PolishDualFixed<3>(p, dual, v, u);
    case 4:
      return PolishDualFixed<4>(p, dual, v, u);
    default:
      return PolishDual(p, dual, v, u);
  }
}

}  // namespace ident::internal
