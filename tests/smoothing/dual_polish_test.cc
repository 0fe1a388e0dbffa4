// The dual polish of the MAP smoother's certificate (ident/smoothing/internal/dual_polish.h) against a dense
// reference: the polish is the projection of (v, u) onto the dual constraint rho(v, u) = A'v - H'u = 0 in the
// metric of the Newton weights, min 1/2 |dv|^2_{W^-1} + 1/2 |du|^2_{Wg^-1} subject to rho(v + dv, u + du) = 0,
// whose solution is d = -Wd C' (C Wd C')^-1 rho with C = [A', -H'] and Wd = blkdiag(W_t, Wg_t), solved
// here with the whole constraint matrix written out.
#include "ident/smoothing/internal/dual_polish.h"
#include "common/dense_decompositions.h"

#include <random>
#include <string>

#include <gtest/gtest.h>
#include <Eigen/Cholesky>

#include "ident/smoothing/map_smoother.h"
#include "tests/smoothing/random_matrices.h"

namespace ident {
namespace {

using duality_test::RandomMatrix;
using duality_test::RandomSpd;

struct PolishCase {
  MapSmootherProblem problem;
  internal::MapSmootherDualIterate dual;
  Eigen::MatrixXd v, u;
};

// T + 1 steps, n states, nz measurements; time-varying F and H if `varying`; W_t of {f_0, f} (two
// distinct matrices) and a random Wg_t per step; v and u random.
PolishCase MakeCase(std::mt19937& rng, int n, int nz, int T, bool varying) {
  PolishCase c;
  MapSmootherProblem& p = c.problem;
  const int num_f = varying ? T : 1, num_h = varying ? T + 1 : 1;
  for (int t = 0; t < num_f; ++t) p.F.push_back(RandomMatrix(rng, n, n, 0.6));
  for (int t = 0; t < num_h; ++t) p.H.push_back(RandomMatrix(rng, nz, n));
  p.z = Eigen::MatrixXd::Zero(nz, T + 1);
  const Eigen::MatrixXd W0 = RandomSpd(rng, n), W = RandomSpd(rng, n, 3.0);
  c.dual.process_weight.resize(n * n, T + 1);
  c.dual.measurement_weight.resize(nz * nz, T + 1);
  for (int t = 0; t <= T; ++t) {
    c.dual.process_weight.col(t) = Eigen::Map<const Eigen::VectorXd>((t == 0 ? W0 : W).data(), n * n);
    const Eigen::MatrixXd Wg = RandomSpd(rng, nz, 0.5);
    c.dual.measurement_weight.col(t) = Eigen::Map<const Eigen::VectorXd>(Wg.data(), nz * nz);
  }
  c.v = RandomMatrix(rng, n, T + 1);
  c.u = RandomMatrix(rng, nz, T + 1);
  return c;
}

// rho(v, u) stacked by step: rho_t = v_t - F_t'v_{t+1} - H_t'u_t.
Eigen::VectorXd Residual(const MapSmootherProblem& p, const Eigen::MatrixXd& v, const Eigen::MatrixXd& u) {
  const int T = p.T(), n = p.state_dim();
  Eigen::VectorXd rho(n * (T + 1));
  for (int t = 0; t <= T; ++t) {
    Eigen::VectorXd r = v.col(t) - p.Ht(t).transpose() * u.col(t);
    if (t < T) r -= p.Ft(t).transpose() * v.col(t + 1);
    rho.segment(n * t, n) = r;
  }
  return rho;
}

// The weighted projection written out: C = [A', -H'] on x = [v (step-major); u (step-major)].
void DenseProjection(const PolishCase& c, Eigen::MatrixXd* v, Eigen::MatrixXd* u) {
  const MapSmootherProblem& p = c.problem;
  const int T = p.T(), n = p.state_dim(), nz = p.measurement_dim(), N = T + 1;
  const int nv = n * N, nu = nz * N;
  Eigen::MatrixXd C = Eigen::MatrixXd::Zero(nv, nv + nu), Wd = Eigen::MatrixXd::Zero(nv + nu, nv + nu);
  for (int t = 0; t <= T; ++t) {
    C.block(n * t, n * t, n, n).setIdentity();
    if (t < T) C.block(n * t, n * (t + 1), n, n) = -p.Ft(t).transpose();
    C.block(n * t, nv + nz * t, n, nz) = -p.Ht(t).transpose();
    Wd.block(n * t, n * t, n, n) = Eigen::Map<const Eigen::MatrixXd>(c.dual.process_weight.col(t).data(), n, n);
    Wd.block(nv + nz * t, nv + nz * t, nz, nz) =
        Eigen::Map<const Eigen::MatrixXd>(c.dual.measurement_weight.col(t).data(), nz, nz);
  }
  const Eigen::VectorXd rho = Residual(p, c.v, c.u);
  const Eigen::VectorXd d = -Wd * C.transpose() * dense::Ldlt(C * Wd * C.transpose()).solve(rho);
  *v = c.v + Eigen::Map<const Eigen::MatrixXd>(d.data(), n, N);
  *u = c.u + Eigen::Map<const Eigen::MatrixXd>(d.data() + nv, nz, N);
}

TEST(DualPolish, EqualsTheWeightedProjectionOntoTheDualConstraint) {
  std::mt19937 rng(17);
  for (int n : {1, 2, 3, 4, 6})  // 1..4: the fixed-size blocks; 6: any size
    for (int nz : {1, 2})
      for (bool varying : {false, true}) {
        const std::string label =
            "n = " + std::to_string(n) + ", nz = " + std::to_string(nz) + (varying ? ", time-varying" : "");
        const PolishCase c = MakeCase(rng, n, nz, 30, varying);
        Eigen::MatrixXd v_ref, u_ref;
        DenseProjection(c, &v_ref, &u_ref);
        Eigen::MatrixXd v = c.v, u = c.u;
        const double before = Residual(c.problem, v, u).cwiseAbs().maxCoeff();
        const double after = internal::PolishMapSmootherDual(c.problem, c.dual, &v, &u);
        EXPECT_NEAR(after, Residual(c.problem, v, u).cwiseAbs().maxCoeff(), 1e-15 * before) << label;
        EXPECT_LT(after, 1e-12 * before) << label;
        const double scale = 1 + v_ref.cwiseAbs().maxCoeff() + u_ref.cwiseAbs().maxCoeff();
        EXPECT_LT((v - v_ref).cwiseAbs().maxCoeff(), 1e-9 * scale) << label;
        EXPECT_LT((u - u_ref).cwiseAbs().maxCoeff(), 1e-9 * scale) << label;
      }
}

TEST(DualPolish, OneWeightColumnPerProcessPenaltyEqualsOnePerStep) {
  std::mt19937 rng(5);
  for (int n : {2, 6}) {
    PolishCase c = MakeCase(rng, n, 1, 40, false);  // W_0 at t = 0, W at every later step
    Eigen::MatrixXd v_steps = c.v, u_steps = c.u;
    internal::PolishMapSmootherDual(c.problem, c.dual, &v_steps, &u_steps);
    c.dual.process_weight = Eigen::MatrixXd(c.dual.process_weight.leftCols(2));
    ASSERT_EQ(internal::ProcessWeightColumn(c.dual.process_weight, 7), 1);
    Eigen::MatrixXd v_penalties = c.v, u_penalties = c.u;
    internal::PolishMapSmootherDual(c.problem, c.dual, &v_penalties, &u_penalties);
    EXPECT_EQ(v_penalties, v_steps) << "n = " << n;
    EXPECT_EQ(u_penalties, u_steps) << "n = " << n;
  }
}

}  // namespace
}  // namespace ident
