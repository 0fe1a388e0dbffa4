// Indirect self-tuning regulator on a drifting second-order plant with rare gross measurement outliers.
//
// Problem: control y to a square-wave reference r while the plant's parameters drift; the sensor
//   occasionally returns garbage. The regulator re-identifies an ARX(2,2,1) model every sample and
//   re-designs a pole-placement RST controller from it (ident/control/pole_placement.h).
// Plant:   y(t) = −a1(t) y(t−1) − a2(t) y(t−2) + b1(t) u(t−1) + b2 u(t−2) + e(t),  e ~ N(0, 0.1²)
//          a1 = −1.5 + 0.1 sin(2πt/4000), a2 = 0.7 − 0.05 sin(2πt/3000), b1 = 1 + 0.2 sin(2πt/5000),
//          b2 = 0.5;  measured y_m(t) = y(t) + o(t), o(t) = ±U(5, 10) with probability 1 %, else 0.
// Loop:    warm-up: 100 samples of random ±1 input; then u from R u = T r − S y_m with
//          Am = (1 − 0.6q⁻¹)², Ao = 1 − 0.3q⁻¹, integral action, |u| ≤ 20.
// Models:  (a) RLS with exponential forgetting λ = 0.99;
//          (b) the Cauchy (Kárný–Hangos) estimator with the same forgetting — when built in (IDENT_HAS_CAUCHY).
// Output:  per estimator, mean over seeded runs of
//          output variance  Var(y − y_d) (true y against the designed response Am y_d = Am(1) r(t−1)),
//          tracking error   RMS(r − y),
//          with and without outliers, and the ratio outliers / outlier-free. Samples t ≥ 500 only.
//          Three tables: the control law fed (1) the raw y_m, (2) y_m validated by the model (its
//          one-step prediction replaces y_m when |y_m − ŷ| > 5σ̂), (3) validated and rejected samples
//          withheld from the estimator with Skip(); a "true model" row gives the floor of each.
//          --plot FILE.svg draws run 1 (with outliers; feedback mode --plot-feedback, default
//          validated); --csv FILE writes it.
//
//   ./build/examples/self_tuning_regulator [--runs 20] [--samples 5000] [--plot str.svg] [--csv str.csv]
//                                          [--plot-feedback raw|validated|skip] [--check]
// --check exits 1 unless Var(y − y_d) with outliers stays within 20 % of the outlier-free value for the
// true model and the Cauchy model with validated feedback, and for all models with validated feedback
// + Skip() (CTest runs it with 3 runs of 3000 samples).
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "ident/control/pole_placement.h"
#include "ident/control/rst_controller.h"
#include "ident/regression/rls.h"
#if __has_include("ident/regression/student_regression.h")
#include "ident/regression/student_regression.h"
#define IDENT_HAS_CAUCHY 1
#endif
#ifdef IDENT_HAS_GNUPLOT
#include "cli/gnuplot.h"
#endif

namespace {

constexpr double kForgetting = 0.99;
constexpr int kBurnIn = 500;
constexpr int kWarmUp = 100;
constexpr double kPi = 3.14159265358979323846;

struct Trace {
  std::vector<double> t, r, y, y_measured, u, a1, a1_hat, b1, b1_hat;
};

// What the control law sees: the raw measurement, or a validated one — the model's one-step
// prediction θ̂'z replaces y_m when |y_m − θ̂'z| > 5σ̂ (σ̂ = the estimator's noise_std()). kSkip also
// withholds rejected samples from the estimator (Skip(): state untouched).
enum class Feedback { kRaw, kValidated, kValidatedSkip };

struct Metrics {
  double output_variance = 0;
  double tracking_rms = 0;
};

// One closed-loop run. The plant noise and the outliers come from separate seeded streams, so every
// estimator sees the same disturbances, and the outlier-free run the same plant noise.
template <class Estimator>
Metrics RunLoop(Estimator& est, unsigned seed, int samples, bool outliers, Feedback feedback, Trace* trace) {
  std::mt19937 noise_rng(seed), outlier_rng(seed + 7919), input_rng(seed + 104729);
  std::normal_distribution<double> noise(0, 0.1);
  std::uniform_real_distribution<double> unit(0, 1);
  ident::control::PolePlacementOptions design_options;
  design_options.am = Eigen::Vector3d(1, -1.2, 0.36);
  design_options.ao = Eigen::Vector2d(1, -0.3);
  design_options.integral_action = true;
  ident::control::PolePlacement design(2, 2, 1, design_options);
  ident::control::RstController law(static_cast<int>(design.R().size()) - 1, static_cast<int>(design.S().size()) - 1,
                                    static_cast<int>(design.T().size()) - 1, /*u_max=*/20);
  const Eigen::Vector3d am = design_options.am;
  double y1 = 0, y2 = 0, ym1 = 0, ym2 = 0, u1 = 0, u2 = 0, yd1 = 0, yd2 = 0, r1 = 0;
  double sum_e = 0, sum_e2 = 0, sum_track2 = 0;
  int count = 0;
  Eigen::Vector4d z;
  for (int t = 0; t < samples; ++t) {
    const double a1 = -1.5 + 0.1 * std::sin(2 * kPi * t / 4000), a2 = 0.7 - 0.05 * std::sin(2 * kPi * t / 3000);
    const double b1 = 1 + 0.2 * std::sin(2 * kPi * t / 5000), b2 = 0.5;
    const double y = -a1 * y1 - a2 * y2 + b1 * u1 + b2 * u2 + noise(noise_rng);
    double o = 0;
    const bool hit = unit(outlier_rng) < 0.01;
    const double magnitude = 5 + 5 * unit(outlier_rng), sign = unit(outlier_rng) < 0.5 ? -1 : 1;
    if (outliers && hit) o = sign * magnitude;
    const double y_measured = y + o;
    // Identification: z(t) = [−y_m(t−1), −y_m(t−2), u(t−1), u(t−2)], θ = [a1, a2, b1, b2].
    // (ym1, ym2: the past fed-back outputs — the measured ones, or in validated modes the validated ones.)
    z << -ym1, -ym2, u1, u2;
    if constexpr (requires { est.SetTruth(Eigen::Vector4d()); }) est.SetTruth(Eigen::Vector4d(a1, a2, b1, b2));
    const double prediction = est.parameters().dot(z);  // θ̂(t−1)'z(t)
    const double scale = est.noise_std();
    const bool suspect = feedback != Feedback::kRaw && t >= kWarmUp && std::abs(y_measured - prediction) > 5 * scale;
    const double y_feedback = suspect ? prediction : y_measured;
    if (suspect && feedback == Feedback::kValidatedSkip) {
      if constexpr (requires { est.Skip(); }) est.Skip();  // (not updating is the same: state untouched)
    } else {
      est.Update(y_measured, z);
    }
    const auto& theta = est.parameters();
    // Design (keeps the last good controller if the model is not controllable) and control.
    if (design.Design(theta.head(2), theta.tail(2)) == ident::control::DesignStatus::kOk)
      law.set_polynomials(design.R(), design.S(), design.T());
    const double r = (t / 200) % 2 == 0 ? 1.0 : -1.0;
    double u = law.Control(r, y_feedback);
    if (t < kWarmUp) u = unit(input_rng) < 0.5 ? -1.0 : 1.0;
    // Designed response Am y_d = Am(1) r(t−1).
    const double yd = -am(1) * yd1 - am(2) * yd2 + am.sum() * r1;
    if (t >= kBurnIn) {
      const double e = y - yd;
      sum_e += e, sum_e2 += e * e, sum_track2 += (r - y) * (r - y);
      ++count;
    }
    if (trace) {
      trace->t.push_back(t), trace->r.push_back(r), trace->y.push_back(y), trace->y_measured.push_back(y_measured);
      trace->u.push_back(u), trace->a1.push_back(a1), trace->a1_hat.push_back(theta(0));
      trace->b1.push_back(b1), trace->b1_hat.push_back(theta(2));
    }
    y2 = y1, y1 = y, ym2 = ym1, ym1 = y_feedback, u2 = u1, u1 = u, yd2 = yd1, yd1 = yd, r1 = r;
  }
  const double mean = sum_e / count;
  return {sum_e2 / count - mean * mean, std::sqrt(sum_track2 / count)};
}

// Reference "estimator" that knows the true θ(t): the loop's floor (what a perfect model achieves with
// the same raw measurements in the feedback path).
struct TrueModel {
  Eigen::Vector4d theta = Eigen::Vector4d::Zero();
  void SetTruth(const Eigen::Vector4d& truth) { theta = truth; }
  ident::StepReport Update(double, const Eigen::Vector4d&) { return {}; }
  ident::StepReport Skip() { return {ident::StepStatus::kSkipped}; }
  double noise_std() const { return 0.1; }
  const Eigen::Vector4d& parameters() const { return theta; }
};

ident::RegressionPrior Prior() { return ident::RegressionPrior::Diagonal(4, 6, 1, 1e-3); }

struct Row {
  const char* name;
  Metrics clean, outliers;
};

template <class MakeEstimator>
Row Study(const char* name, MakeEstimator make, int runs, int samples, Feedback feedback) {
  Row row{name, {}, {}};
  for (int run = 1; run <= runs; ++run)
    for (const bool outliers : {false, true}) {
      auto est = make();
      const Metrics m = RunLoop(est, static_cast<unsigned>(run), samples, outliers, feedback, nullptr);
      Metrics& acc = outliers ? row.outliers : row.clean;
      acc.output_variance += m.output_variance / runs;
      acc.tracking_rms += m.tracking_rms / runs;
    }
  return row;
}

void WriteCsv(const std::string& path, const Trace& a, const Trace* b) {
  std::ofstream out(path);
  out << "t,r,y_true_rls,y_measured_rls,u_rls,a1,a1_hat_rls,b1,b1_hat_rls";
  if (b) out << ",y_true_cauchy,u_cauchy,a1_hat_cauchy,b1_hat_cauchy";
  out << "\n";
  for (size_t i = 0; i < a.t.size(); ++i) {
    out << a.t[i] << ',' << a.r[i] << ',' << a.y[i] << ',' << a.y_measured[i] << ',' << a.u[i] << ',' << a.a1[i] << ','
        << a.a1_hat[i] << ',' << a.b1[i] << ',' << a.b1_hat[i];
    if (b) out << ',' << b->y[i] << ',' << b->u[i] << ',' << b->a1_hat[i] << ',' << b->b1_hat[i];
    out << '\n';
  }
}

}  // namespace

int main(int argc, char** argv) {
  int runs = 20, samples = 5000;
  bool check = false;
  std::string plot, csv, plot_feedback = "validated";
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--check") {
      check = true;
      continue;
    }
    if (i + 1 >= argc) {
      std::fprintf(stderr,
                   "usage: %s [--runs N] [--samples N] [--plot FILE.svg|.png] [--csv FILE] "
                   "[--plot-feedback raw|validated|skip] [--check]\n",
                   argv[0]);
      return 2;
    }
    const std::string value = argv[++i];
    if (arg == "--runs")
      runs = std::atoi(value.c_str());
    else if (arg == "--samples")
      samples = std::atoi(value.c_str());
    else if (arg == "--plot")
      plot = value;
    else if (arg == "--csv")
      csv = value;
    else if (arg == "--plot-feedback")
      plot_feedback = value;
    else {
      std::fprintf(stderr, "unknown option %s\n", arg.c_str());
      return 2;
    }
  }
  Feedback plotted = Feedback::kValidated;
  if (plot_feedback == "raw")
    plotted = Feedback::kRaw;
  else if (plot_feedback == "skip")
    plotted = Feedback::kValidatedSkip;
  else if (plot_feedback != "validated") {
    std::fprintf(stderr, "--plot-feedback %s: need raw, validated or skip\n", plot_feedback.c_str());
    return 2;
  }
  if (runs < 1 || samples <= kBurnIn + 10) {
    std::fprintf(stderr, "need --runs >= 1 and --samples > %d\n", kBurnIn + 10);
    return 2;
  }

  auto make_rls = [] {
    ident::RlsOptions o;
    o.forgetting.factor = kForgetting;
    o.prior = Prior();
    return ident::BasicRecursiveLeastSquares<4>(4, o);
  };
  auto make_truth = [] { return TrueModel(); };
#ifdef IDENT_HAS_CAUCHY
  auto make_cauchy = [] {
    ident::StudentRegressionOptions o;  // k = 1: Cauchy
    o.forgetting.factor = kForgetting;
    o.prior = Prior();
    return ident::BasicStudentRegression<4>(4, o);
  };
#endif
  struct Table {
    const char* title;
    std::vector<Row> rows;
  };
  std::vector<Table> tables;
  for (const Feedback feedback : {Feedback::kRaw, Feedback::kValidated, Feedback::kValidatedSkip}) {
    Table table{feedback == Feedback::kRaw ? "control law fed the raw measurement y_m"
                : feedback == Feedback::kValidated
                    ? "control law fed y_m validated by the model (|y_m - yhat| > 5 sigma: use yhat)"
                    : "validated, and rejected samples withheld from the estimator (Skip())",
                {}};
    table.rows.push_back(Study("true model (floor)", make_truth, runs, samples, feedback));
    table.rows.push_back(Study("RLS, lambda = 0.99", make_rls, runs, samples, feedback));
#ifdef IDENT_HAS_CAUCHY
    table.rows.push_back(Study("Cauchy, lambda = 0.99", make_cauchy, runs, samples, feedback));
#endif
    tables.push_back(table);
  }

  std::printf(
      "Indirect STR (pole placement), drifting ARX(2,2,1) plant, %d seeded runs x %d samples "
      "(statistics over t >= %d)\n",
      runs, samples, kBurnIn);
  for (const Table& table : tables) {
    std::printf("\n%s\n", table.title);
    std::printf("%-24s %15s %14s %8s   %14s %12s %8s\n", "model from", "Var(y-yd) clean", "with outliers", "ratio",
                "RMS(r-y) clean", "w/ outliers", "ratio");
    for (const Row& row : table.rows)
      std::printf("%-24s %15.5f %14.5f %8.3f   %14.5f %12.5f %8.3f\n", row.name, row.clean.output_variance,
                  row.outliers.output_variance, row.outliers.output_variance / row.clean.output_variance,
                  row.clean.tracking_rms, row.outliers.tracking_rms,
                  row.outliers.tracking_rms / row.clean.tracking_rms);
  }

  if (!plot.empty() || !csv.empty()) {
    Trace rls_trace;
    auto rls = make_rls();
    RunLoop(rls, 1, samples, true, plotted, &rls_trace);
    Trace* cauchy_ptr = nullptr;
#ifdef IDENT_HAS_CAUCHY
    Trace cauchy_trace;
    auto cauchy = make_cauchy();
    RunLoop(cauchy, 1, samples, true, plotted, &cauchy_trace);
    cauchy_ptr = &cauchy_trace;
#endif
    if (!csv.empty()) {
      WriteCsv(csv, rls_trace, cauchy_ptr);
      std::printf("wrote %s\n", csv.c_str());
    }
    if (!plot.empty()) {
#ifdef IDENT_HAS_GNUPLOT
      using ident::cli::PlotPanel;
      std::vector<PlotPanel> panels;
      PlotPanel p1{.title = "run 1 with outliers (feedback: " + plot_feedback + "): RLS-based loop",
                   .xlabel = "t",
                   .ylabel = "y",
                   .series = {}};
      p1.series.push_back({"true output y", rls_trace.t, rls_trace.y});
      p1.series.push_back({"reference r", rls_trace.t, rls_trace.r});
      panels.push_back(p1);
      PlotPanel p3{.title = "estimated a1 (true a1 drifts)", .xlabel = "t", .ylabel = "a1", .series = {}};
      p3.series.push_back({"true a1", rls_trace.t, rls_trace.a1});
      p3.series.push_back({"RLS", rls_trace.t, rls_trace.a1_hat});
      if (cauchy_ptr) {
        PlotPanel p2{.title = "run 1 with outliers (feedback: " + plot_feedback + "): Cauchy-based loop",
                     .xlabel = "t",
                     .ylabel = "y",
                     .series = {}};
        p2.series.push_back({"true output y", cauchy_ptr->t, cauchy_ptr->y});
        p2.series.push_back({"reference r", cauchy_ptr->t, cauchy_ptr->r});
        panels.push_back(p2);
        p3.series.push_back({"Cauchy", cauchy_ptr->t, cauchy_ptr->a1_hat});
      }
      panels.push_back(p3);
      ident::cli::RenderPlot(plot, panels);
      std::printf("wrote %s\n", plot.c_str());
#else
      std::fprintf(stderr, "built without the gnuplot helper (tools/); use --csv\n");
      return 1;
#endif
    }
  }
  if (check) {
    // The goal in the loops where the feedback path is protected: every model that is not
    // thrown off by outliers keeps Var(y − y_d) within 20 % of its outlier-free value.
    int failures = 0;
    for (size_t k = 1; k < tables.size(); ++k)
      for (const Row& row : tables[k].rows) {
        const bool robust_here = std::string(row.name).rfind("RLS", 0) != 0 || k == 2;  // RLS only with Skip()
        const double ratio = row.outliers.output_variance / row.clean.output_variance;
        if (robust_here && !(ratio <= 1.2)) {
          std::printf("CHECK FAILED: %s, %s: variance ratio %.3f > 1.2\n", tables[k].title, row.name, ratio);
          ++failures;
        }
      }
    std::printf("%s\n", failures ? "check failed" : "check passed: variance ratio <= 1.2 in the protected loops");
    return failures ? 1 : 0;
  }
  return 0;
}
