#include "ident/smoothing/internal/dual_polish.h"

#include <algorithm>
#include <vector>

#include <Eigen/Cholesky>

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

// PolishMapSmootherDual (dual_polish.h) for a state dimension fixed at compile time: the same rounds on n x n blocks held by value,
// N's block Cholesky (C_t C_t' = D_t - G_t G_t', G_t = E_t C_{t-1}^-T, as ident/linalg/block_tridiagonal.h)
// formed step by step from the weights, and no allocation inside the rounds.
template <int kN>
double PolishDualFixed(const MapSmootherProblem& p, const MapSmootherDualIterate& dual, Eigen::MatrixXd* v_out,
                       Eigen::MatrixXd* u_out) {
  using MatN = Eigen::Matrix<double, kN, kN>;
  using VecN = Eigen::Matrix<double, kN, 1>;
  const int T = p.T(), N = T + 1, nz = p.measurement_dim();
  Eigen::MatrixXd& v = *v_out;
  Eigen::MatrixXd& u = *u_out;
  const auto F = [&](int t) { return Eigen::Map<const MatN>(p.Ft(t).data()); };
  const auto W = [&](int t) { return Eigen::Map<const MatN>(dual.process_weight.col(t).data()); };
  const auto col = [](Eigen::MatrixXd& m, int t) { return Eigen::Map<VecN>(m.col(t).data()); };
  // H_t'b (b: nz entries) and H_t x; H_t is nz x n, column-major.
  const auto add_ht = [&](int t, const double* b, double alpha, VecN& out) {
    const double* H = p.Ht(t).data();
    for (int i = 0; i < kN; ++i) {
      double s = 0;
      for (int j = 0; j < nz; ++j) s += H[j + i * nz] * b[j];
      out(i) += alpha * s;
    }
  };
  Eigen::Matrix<double, kN, Eigen::Dynamic> rho(kN, N);
  const auto residual = [&] {  // rho_t = v_t - F_t'v_{t+1} - H_t'u_t
    double largest = 0;
    for (int t = 0; t <= T; ++t) {
      VecN r = col(v, t);
      if (t < T) r.noalias() -= F(t).transpose() * col(v, t + 1);
      add_ht(t, u.col(t).data(), -1.0, r);
      rho.col(t) = r;
      largest = std::max(largest, r.cwiseAbs().maxCoeff());
    }
    return largest;
  };
  double rho_max = residual();
  if (!(rho_max > 0) || !dual.process_weight.allFinite() || !dual.measurement_weight.allFinite()) return rho_max;
  // N = sum J'WJ: D_t = W_t + F_t'W_{t+1}F_t + H_t'Wg_t H_t, E_t = -W_t F_{t-1}; its block LDL' with
  // P_t = S_t^-1, S_t = D_t - E_t P_{t-1} E_t', kept as P_t, M_t = P_t E_t and N_t = P_t E_{t+1}', so that
  // the substitutions' recurrences take one matrix-vector product per step: g_t = P_t b_t - M_t g_{t-1},
  // x_t = g_t - N_t x_{t+1}.
  std::vector<MatN, Eigen::aligned_allocator<MatN>> P(N), M(N), Nx(N);
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
    MatN E = MatN::Zero();
    if (t > 0) {
      E.noalias() = -W(t) * F(t - 1);
      S.noalias() -= E * P[t - 1] * E.transpose();
      Nx[t - 1].noalias() = P[t - 1] * E.transpose();
    }
    const Eigen::LLT<MatN> llt(S);
    if (llt.info() != Eigen::Success) return rho_max;
    P[t] = llt.solve(MatN::Identity());
    if (!P[t].allFinite()) return rho_max;
    M[t].noalias() = P[t] * E;
  }
  Nx[T].setZero();
  Eigen::Matrix<double, kN, Eigen::Dynamic> xi(kN, N);
  Eigen::MatrixXd v_prev(v.rows(), v.cols()), u_prev(u.rows(), u.cols());
  for (int round = 0; round < 2; ++round) {
    v_prev = v;
    u_prev = u;
    VecN g = VecN::Zero();
    for (int t = 0; t <= T; ++t) {  // b = -rho
      g = -(P[t] * rho.col(t)) - M[t] * g;
      xi.col(t) = g;
    }
    VecN x = VecN::Zero();
    for (int t = T; t >= 0; --t) {
      x = xi.col(t) - Nx[t] * x;
      xi.col(t) = x;
    }
    for (int t = 0; t <= T; ++t) {  // v_t += W_t (A xi)_t, (A xi)_t = xi_t - F_{t-1} xi_{t-1};  u_t -= Wg_t H_t xi_t
      VecN a = xi.col(t);
      if (t > 0) a.noalias() -= F(t - 1) * xi.col(t - 1);
      col(v, t).noalias() += W(t) * a;
      const double* H = p.Ht(t).data();
      const double* Wg = dual.measurement_weight.col(t).data();
      double* ut = u.col(t).data();
      for (int i = 0; i < nz; ++i) {
        double hx = 0;
        for (int k = 0; k < kN; ++k) hx += H[i + k * nz] * xi(k, t);
        for (int j = 0; j < nz; ++j) ut[j] -= Wg[j + i * nz] * hx;
      }
    }
    if (!KeepRound(residual(), &rho_max, v, u, v_prev, u_prev)) break;
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
    const double* W = dual.process_weight.col(t).data();
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
      AddMatVec(dual.process_weight.col(t).data(), n, n, a, v.col(t).data(), 1.0);
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
