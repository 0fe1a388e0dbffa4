// Long-run numerical health of the LD-form regression estimators (a study, not a CI test).
//
//   numerical_health [UPDATES=100000000] [CHECK_EVERY=100000] [SEED=1]
//
// Stream: y(t) = θ'z(t) + e(t), ρ = 4, z(t) ~ N(0, I) white (persistently exciting),
//         e(t) ~ N(0, 0.1²) except with probability 1 % a gross outlier e(t) ~ N(0, 10²) (100 σ).
// Estimators, each with exponential forgetting λ = 0.999 (window ≈ 1000 samples):
//   - LD-form RLS (ident/regression/rls.h);
//   - the Kárný–Hangos Cauchy estimator (ident/regression/student_regression.h, k = 1, δ = 1) with the spec §8
//     prior (`exact`: ν(0) = ρ+k+δ, V(0) = diag(1, 1e-3·I)); both use V(t) = (1−β)Ṽ + βhh'.
// Checks:
//   - min over every step of min_i d_i (D stays positive) and the number of steps not taken;
//   - max over every step after the first window of ‖θ̂ − θ‖ (parameter error bounded);
//   - a reference V accumulated in long double with the same recursion V ← (1−β)V + βhh' (β from
//     each step's report), compared every CHECK_EVERY steps: ‖L'DL − V_ref‖_F/‖V_ref‖_F, and V_ref
//     re-factorised from scratch: max |L − L_ref|, max |d − d_ref|/d_ref, ‖θ̂ − θ_ref‖/‖θ_ref‖.
// Prints the worst of each figure; exit code 1 if D ever stopped being positive or a figure is
// non-finite.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <random>

#include <fmt/core.h>
#include <Eigen/Core>
#include <Eigen/Dense>

#include "ident/linalg/ld_factor.h"
#include "ident/regression/rls.h"
#include "ident/regression/student_regression.h"

namespace {

constexpr int kRho = 4;
using VectorL = Eigen::Matrix<long double, kRho + 1, 1>;
using MatrixL = Eigen::Matrix<long double, kRho + 1, kRho + 1>;

struct Worst {
  double min_d = std::numeric_limits<double>::infinity();  // over every step
  double min_d_after_burn_in = std::numeric_limits<double>::infinity();
  double max_param_error = 0;      // ‖θ̂ − θ‖ after the first window
  double max_v_error = 0;          // ‖L'DL − V_ref‖_F / ‖V_ref‖_F
  double max_l_error = 0;          // max |L − L_ref|
  double max_d_error = 0;          // max |d − d_ref| / d_ref
  double max_theta_ref_error = 0;  // ‖θ̂ − θ_ref‖ / ‖θ_ref‖
  long not_updated = 0;
  long checks = 0;
};

template <class Estimator>
Worst Run(Estimator& est, long updates, long check_every, unsigned seed, double lambda) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n01;
  std::uniform_real_distribution<double> uniform;
  const Eigen::Matrix<double, kRho, 1> theta(1.0, -0.5, 0.25, 2.0);
  Eigen::Matrix<double, kRho, 1> z;
  Eigen::Matrix<double, kRho + 1, 1> h;
  // Reference: the same normalised recursion in long double, started from the estimator's V(0).
  MatrixL V = est.statistics().V().template cast<long double>();
  const long burn_in = static_cast<long>(10 / (1 - lambda));
  Worst w;
  for (long t = 1; t <= updates; ++t) {
    for (int i = 0; i < kRho; ++i) z(i) = n01(rng);
    const double e = uniform(rng) < 0.01 ? 10.0 * n01(rng) : 0.1 * n01(rng);
    const double y = theta.dot(z) + e;
    const ident::StepReport r = est.Update(y, z);
    if (!r.updated()) {
      ++w.not_updated;
      continue;
    }
    h << y, z;
    const VectorL hl = h.cast<long double>();
    const long double beta = r.weight;
    V = (1 - beta) * V + beta * (hl * hl.transpose());
    const auto& f = est.statistics().factor();
    w.min_d = std::min(w.min_d, f.d().minCoeff());
    if (t > burn_in) {
      w.min_d_after_burn_in = std::min(w.min_d_after_burn_in, f.d().minCoeff());
      w.max_param_error = std::max(w.max_param_error, (est.parameters() - theta).norm());
    }
    if (t % check_every == 0 || t == updates) {
      ++w.checks;
      const Eigen::MatrixXd Vd = V.cast<double>();
      w.max_v_error = std::max(w.max_v_error, static_cast<double>((est.statistics().V() - Vd).norm() / Vd.norm()));
      const ident::LdFactor<> ref(Vd);  // re-factorised from scratch
      w.max_l_error =
          std::max(w.max_l_error, (Eigen::MatrixXd(f.L()) - Eigen::MatrixXd(ref.L())).cwiseAbs().maxCoeff());
      w.max_d_error =
          std::max(w.max_d_error, ((Eigen::VectorXd(f.d()) - ref.d()).cwiseAbs().cwiseQuotient(ref.d())).maxCoeff());
      const Eigen::Matrix<long double, kRho, 1> theta_ref =
          V.bottomRightCorner(kRho, kRho).ldlt().solve(V.bottomLeftCorner(kRho, 1));
      const Eigen::Matrix<double, kRho, 1> theta_refd = theta_ref.cast<double>();
      w.max_theta_ref_error =
          std::max(w.max_theta_ref_error, (est.parameters() - theta_refd).norm() / theta_refd.norm());
    }
  }
  return w;
}

bool Report(const char* name, const Worst& w, long updates, double seconds) {
  fmt::print("{}: {} updates in {:.1f} s, {} not taken, {} reference checks\n", name, updates, seconds, w.not_updated,
             w.checks);
  fmt::print("  min d_i over all steps                    {:.3e}  (the flat prior's start)\n", w.min_d);
  fmt::print("  min d_i after burn-in (10 windows)        {:.3e}\n", w.min_d_after_burn_in);
  fmt::print("  max ||theta_hat - theta|| after burn-in   {:.3e}\n", w.max_param_error);
  fmt::print("  max ||L'DL - V_ref||_F / ||V_ref||_F      {:.3e}\n", w.max_v_error);
  fmt::print("  max |L - L_ref| (re-factorised V_ref)     {:.3e}\n", w.max_l_error);
  fmt::print("  max |d - d_ref| / d_ref                   {:.3e}\n", w.max_d_error);
  fmt::print("  max ||theta_hat - theta_ref|| / ||theta_ref||  {:.3e}\n", w.max_theta_ref_error);
  return w.min_d > 0 && std::isfinite(w.max_param_error) && std::isfinite(w.max_v_error) &&
         std::isfinite(w.max_l_error) && std::isfinite(w.max_d_error) && std::isfinite(w.max_theta_ref_error);
}

}  // namespace

int main(int argc, char** argv) {
  const long updates = argc > 1 ? std::atol(argv[1]) : 100'000'000L;
  const long check_every = argc > 2 ? std::atol(argv[2]) : 100'000L;
  const unsigned seed = argc > 3 ? static_cast<unsigned>(std::atol(argv[3])) : 1u;
  if (updates < 1 || check_every < 1) {
    std::fprintf(stderr, "usage: numerical_health [UPDATES>=1] [CHECK_EVERY>=1] [SEED]\n");
    return 2;
  }
  constexpr double kLambda = 0.999;
  fmt::print("stream: rho = {}, z ~ N(0,I), e ~ N(0,0.1^2) with 1 % outliers N(0,10^2); forgetting {}\n", kRho,
             kLambda);
  bool ok = true;
  {
    ident::RlsOptions options;
    options.forgetting.factor = kLambda;
    ident::BasicRecursiveLeastSquares<kRho> rls(kRho, options);
    const auto start = std::chrono::steady_clock::now();
    const Worst w = Run(rls, updates, check_every, seed, kLambda);
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    ok &= Report("LD-form RLS", w, updates, s);
  }
  {
    ident::StudentRegressionOptions options;  // Cauchy: k = 1, δ = 1
    options.exact = true;                     // spec §8 prior, no data-driven start-up
    options.forgetting.factor = kLambda;
    ident::BasicStudentRegression<kRho> cauchy(kRho, options);
    const auto start = std::chrono::steady_clock::now();
    const Worst w = Run(cauchy, updates, check_every, seed, kLambda);
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    ok &= Report("Cauchy (Karny-Hangos, k = 1)", w, updates, s);
  }
  return ok ? 0 : 1;
}
