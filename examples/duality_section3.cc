// The example of section 3 of Bassett, Casey & Wets, "Log-Concave Duality in Estimation and Control":
// reconstructing the MAP state estimate from the solution of the dual control problem.
//
//   Model:  x_{t+1} = [[1, 1], [0, 1]] x_t + w_{t+1},  x_0 = w_0,  w_t ~ N(0, I)    (position, velocity)
//           z_t = [1 1] x_t + v_t,  v_t ~ Laplace(0, 1),  t = 0..10
//   MAP:    f_t = 1/2 |w|^2;  g = -log of the log-concave MLE of 100 Laplace(0, 1) samples
//           (piecewise linear, +inf outside the sample range), problem (P_ex).
//   Dual:   (D_ex), solved together with (P) by the interior-point smoother; w* = y* (grad of f* = 1/2|y|^2),
//           then x* from the dynamics.
// Look at: primal and dual values (equal: strong duality, Thm 2.6), the gap, and max |x_primal - x_from_dual|.
// Usage: duality_section3 [--seed N] [--plot FILE.svg]   (the plot needs gnuplot: Debian gnuplot-nox)
#include <cstdlib>
#include <random>
#include <string>

#include <fmt/format.h>

#include "ident/density/logconcave_mle.h"
#include "ident/smoothing/map_smoother.h"
#ifdef IDENT_EXAMPLE_HAS_PLOT
#include "cli/gnuplot.h"
#endif

int main(int argc, char** argv) {
  unsigned seed = 1;
  std::string plot;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--seed" && i + 1 < argc)
      seed = static_cast<unsigned>(std::atoi(argv[++i]));
    else if (arg == "--plot" && i + 1 < argc)
      plot = argv[++i];
    else {
      fmt::print(stderr, "usage: duality_section3 [--seed N] [--plot FILE.svg]\n");
      return 2;
    }
  }
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal(0, 1);
  std::exponential_distribution<double> expo(1.0);
  std::bernoulli_distribution sign(0.5);
  auto laplace = [&] { return (sign(rng) ? 1 : -1) * expo(rng); };

  // Density of the measurement noise: log-concave MLE of 100 Laplace(0, 1) samples.
  std::vector<double> samples(100);
  for (double& s : samples) s = laplace();
  const ident::approx::LogConcaveMle mle = ident::approx::FitLogConcaveMle(samples);
  fmt::print("log-concave MLE of 100 Laplace(0,1) samples: {} knots on [{:.4f}, {:.4f}], loglik {:.6f}\n",
             mle.knots.size(), mle.knots(0), mle.knots(mle.knots.size() - 1), mle.loglik);
  fmt::print("  g*(v) = max_k (v k + phi(k)):  g*(-1) = {:.6f}, g*(0) = {:.6f}, g*(1) = {:.6f}\n",
             mle.ConjugateOfNegativeLogDensity(-1), mle.ConjugateOfNegativeLogDensity(0),
             mle.ConjugateOfNegativeLogDensity(1));

  const int T = 10;
  Eigen::MatrixXd F(2, 2), H(1, 2);
  F << 1, 1, 0, 1;
  H << 1, 1;
  Eigen::MatrixXd truth(2, T + 1), z(1, T + 1);
  for (int t = 0; t <= T; ++t) {
    Eigen::Vector2d w(normal(rng), normal(rng));
    truth.col(t) = t == 0 ? Eigen::VectorXd(w) : Eigen::VectorXd(F * truth.col(t - 1) + w);
    z(0, t) = (H * truth.col(t))(0) + laplace();
  }

  ident::MapSmootherProblem problem;
  problem.F = {F};
  problem.H = {H};
  problem.z = z;
  problem.process = {ident::models::Penalty::Quadratic(Eigen::MatrixXd::Identity(2, 2))};
  problem.measurement = {mle.NegativeLogDensity()};
  const ident::MapSmootherResult r = ident::SolveMapSmoother(problem);
  fmt::print("interior point: {}\n", r.message);
  fmt::print("primal value (P_ex)          {:.12f}\n", r.primal);
  fmt::print("dual value   (D_ex)          {:.12f}\n", r.dual);
  fmt::print("duality gap                  {:.3e}\n", r.gap);
  fmt::print("max |x_primal - x_from_dual| {:.3e}\n\n", r.max_abs_x_difference);
  fmt::print("   t  {:>10} {:>10} {:>10}   {:>10} {:>10} {:>10}\n", "pos true", "pos MAP", "pos dual", "vel true",
             "vel MAP", "vel dual");
  for (int t = 0; t <= T; ++t)
    fmt::print("  {:2d}  {:10.4f} {:10.4f} {:10.4f}   {:10.4f} {:10.4f} {:10.4f}\n", t, truth(0, t), r.x(0, t),
               r.x_from_dual(0, t), truth(1, t), r.x(1, t), r.x_from_dual(1, t));
  if (!plot.empty()) {
#ifdef IDENT_EXAMPLE_HAS_PLOT
    std::vector<double> ts(T + 1);
    for (int t = 0; t <= T; ++t) ts[t] = t;
    std::vector<ident::cli::PlotPanel> panels;
    const char* names[2] = {"position x1", "velocity x2"};
    for (int i = 0; i < 2; ++i) {
      ident::cli::PlotPanel p{.title = names[i], .xlabel = "t", .ylabel = names[i], .series = {}};
      std::vector<double> tr(T + 1), map(T + 1), dual(T + 1);
      for (int t = 0; t <= T; ++t) tr[t] = truth(i, t), map[t] = r.x(i, t), dual[t] = r.x_from_dual(i, t);
      p.series.push_back({"truth", ts, tr});
      p.series.push_back({"MAP estimate (primal)", ts, map});
      p.series.push_back({"reconstructed from the dual", ts, dual});
      panels.push_back(p);
    }
    ident::cli::RenderPlot(plot, panels);
    fmt::print("\nplot written to {}\n", plot);
#else
    fmt::print(stderr, "plotting needs the tools layer (IDENT_BUILD_TOOLS)\n");
    return 1;
#endif
  }
  return r.status == ident::MapSmootherStatus::kConverged ? 0 : 1;
}
