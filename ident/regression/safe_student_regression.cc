#include "ident/regression/safe_student_regression.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "common/dense_decompositions.h"
#include "ident/regression/batch_regression.h"
#include "ident/regression/internal/lagged_output_screen.h"

namespace ident {
namespace {

// The t_k scale² of residuals r (r2 = r²) by the EM fixed point s² = mean(w r²), w = (k+1)/(k + r²/s²)
// (its maximum-likelihood value), from `start`; returns `start` if that is not positive.
double StudentScaleSquared(const Eigen::ArrayXd& r2, double k, double start) {
  double s2 = start;
  for (int iteration = 0; iteration < 200 && s2 > 0; ++iteration) {
    const double next = (r2 * (k + 1) / (k + r2 / s2)).mean();
    const bool done = std::abs(next - s2) <= 1e-10 * s2;
    s2 = next;
    if (done) break;
  }
  return s2;
}

// The estimator that runs until the first restart: the explicit prior, or the provisional one (in the data's
// units if given) without the plain class's own start-up rule.
StudentRegressionOptions Provisional(StudentRegressionOptions o, int rho, const std::optional<Eigen::MatrixXd>& v0) {
  if (!o.exact && !o.prior) {
    if (v0) {
      IDENT_REQUIRE(v0->rows() == rho + 1 && v0->cols() == rho + 1, "provisional V0 is {}x{}; need {}x{}", v0->rows(),
                    v0->cols(), rho + 1, rho + 1);
      o.prior = RegressionPrior{o.DefaultPrior(rho).nu0, *v0};
    }
    o.exact = true;
  }
  if (!o.exact) o.leverage_guard = true;
  return o;
}

int DefaultMonitorWindow(const SafeStudentOptions& o, int rho) {
  IDENT_REQUIRE(o.lock_in_window == 0 || (o.lock_in_window >= 2 && o.lock_in_window <= kMaxLockInWindow),
                "lock_in_window = {}; need 0 (automatic) or 2..{}", o.lock_in_window, kMaxLockInWindow);
  return o.lock_in_window > 0 ? o.lock_in_window : std::max(100, 20 * std::max(rho, 1));
}

// The window's rows without a regressor coordinate beyond kLeverage robust scales of its column (a gross
// output outlier entering later ARX regressors is such a row) and not `poisoned` (their regressor carries an
// output the lagged-output screen flags, internal/lagged_output_screen.h), as long as at least 2ρ+1 rows remain.
Eigen::MatrixXd OrdinaryRows(const Eigen::Ref<const Eigen::MatrixXd>& window,
                             const Eigen::Array<bool, Eigen::Dynamic, 1>& poisoned,
                             Eigen::Array<bool, Eigen::Dynamic, 1>& keep) {
  const Eigen::Index rho = window.cols() - 1, n = window.rows();
  keep = !poisoned;
  for (Eigen::Index j = 1; j <= rho; ++j) {
    Eigen::VectorXd column = window.col(j);
    std::nth_element(column.data(), column.data() + n / 2, column.data() + n);
    const double median = column(n / 2), scale = RobustScale(window.col(j));
    keep = keep && ((window.col(j).array() - median).abs() <= SafeStudentRegression::kLeverage * scale);
  }
  if (keep.count() < 2 * rho + 1) keep.setConstant(true);
  Eigen::MatrixXd kept(keep.count(), rho + 1);
  for (Eigen::Index i = 0, k = 0; i < n; ++i)
    if (keep(i)) kept.row(k++) = window.row(i);
  return kept;
}

// Throws InvalidArgument unless the fit rests on its inliers in every direction: the information of the
// weighted rows, M_w, against that of all kept rows, M_0 = Z'Z/n, generalised eigenvalues ≥ kInlierShare
// (a direction that only a few rows carry, such as a binary input that has switched twice, can be left to
// rows the fit calls outliers, and a start there would be arbitrary); nor may a direction rest on one row:
// every weighted leverage w_i z_i'(Z'WZ)⁻¹z_i ≤ kMaxLeverage (a binary input that has switched once in the
// window leaves the row of the switch to decide its coefficients alone — and to fit a gross outlier there
// exactly). Only a rank-deficient window fails when not `strict`.
void RequireInlierSupport(const Eigen::Ref<const Eigen::MatrixXd>& Z, const Eigen::VectorXd& w,
                          const Eigen::MatrixXd& M, bool strict) {
  constexpr double kInlierShare = 0.1, kMaxLeverage = 0.8;
  const Eigen::MatrixXd M0 = Z.transpose() * Z / static_cast<double>(Z.rows());
  const Eigen::LLT<Eigen::MatrixXd> chol = dense::Llt(M0);
  IDENT_REQUIRE(chol.info() == Eigen::Success, "the window's regressors are rank-deficient");
  const Eigen::MatrixXd Linv = dense::LowerTriangularInverse(chol.matrixLLT());
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> relative =
      dense::SymmetricEigen(Linv * M * Linv.transpose(), Eigen::EigenvaluesOnly);
  IDENT_REQUIRE(relative.eigenvalues()(0) >= kInlierShare || !strict, "a direction rests on the fit's outliers");
  const Eigen::LLT<Eigen::MatrixXd> information = dense::Llt(Z.transpose() * w.asDiagonal() * Z);
  for (Eigen::Index i = 0; i < Z.rows(); ++i) {
    const Eigen::VectorXd zi = Z.row(i).transpose();
    IDENT_REQUIRE(w(i) * zi.dot(information.solve(zi)) <= kMaxLeverage || !strict, "a direction rests on a few rows");
  }
}

// Each window row's influence on Θ_r, for the propagated variance of the replay (PropagatedVariance):
// δΘ_r ≈ (Σψ'_j z_j z_j')⁻¹ Σ ψ_i z_i, in the scalar form ψ_i/Σψ'_j, with the Cauchy score ψ = w·r and its
// slope ψ' = 2(1−u)/(1+u)², u = r²/γ² (Huber 1981, §7.6); rows left out (`keep` false) have none. Returns
// the seed of the propagation: Σ x_i²·q_i/ρ, q_i = z_i'M_w⁻¹z_i.
double WindowInfluence(const Eigen::Ref<const Eigen::MatrixXd>& Z, const Eigen::VectorXd& r, const Eigen::VectorXd& w,
                       double gamma2, const Eigen::MatrixXd& M, const Eigen::Array<bool, Eigen::Dynamic, 1>& keep,
                       Eigen::VectorXd& influence) {
  const Eigen::Index rho = Z.cols();
  const Eigen::ArrayXd u = r.array().square() / gamma2;
  const double slope = (2 * (1 - u) / (1 + u).square()).sum();
  const Eigen::ArrayXd score = w.array() * r.array() / std::max(slope, 0.25 * w.sum());
  influence.setZero(keep.size());
  for (Eigen::Index i = 0, k = 0; i < keep.size(); ++i)
    if (keep(i)) influence(i) = score(k++);
  const Eigen::LLT<Eigen::MatrixXd> metric = dense::Llt(M);
  double seed = 0;
  for (Eigen::Index i = 0; i < Z.rows(); ++i) {
    const Eigen::VectorXd zi = Z.row(i).transpose();
    seed += score(i) * score(i) * zi.dot(metric.solve(zi)) / static_cast<double>(rho);
  }
  return seed;
}

// The prior after a high-breakdown fit of a window of samples (rows (y, z')): Cauchy maximum likelihood from
// elemental-subset starts (ident/regression/batch_regression.h) gives Θ_r, γ and the weights w_i = 2/(1 + r_i²/γ²) of
// its residuals r_i. The prior is the class member [spec §2] of ν0 pseudo-samples centred there (ν0 = W at
// the start-up, where the fit summarises the window; ρ+k+δ at a lock-in restart, which replays everything):
//   V_z(0) = M_w = Σ w_i z_i z_i' / Σ w_i,  V_zy(0) = M_w Θ_r,  V_y(0) = σ0² + Θ_r'M_w Θ_r  (D_y(0) = σ0²),
// σ0 = G^{(k+1)/(2k)}·s_e with s_e = RobustScale of the residuals (spec §8's safe side), or s_y without
// `refine_scale`. So the first replayed samples are weighed against Θ_r, not against a vague prior that the
// first few of them would decide. A window that does not determine every coefficient from its inliers
// has no such start: nullopt (RequireInlierSupport, and the header comment).
// With `strict` = false (the end of the data: no later window can do better) only a rank-deficient window
// has no start.
std::optional<RegressionPrior> RobustWindowPrior(const Eigen::Ref<const Eigen::MatrixXd>& window,
                                                 const Eigen::Array<bool, Eigen::Dynamic, 1>& poisoned,
                                                 const SafeStudentOptions& options, double nu0, double growth,
                                                 bool strict, Eigen::VectorXd& influence, double& seed) {
  const Eigen::Index rho = window.cols() - 1;
  Eigen::Array<bool, Eigen::Dynamic, 1> keep;
  const Eigen::MatrixXd kept = OrdinaryRows(window, poisoned, keep);
  const auto Z = kept.rightCols(rho);
  try {
    CauchyMlOptions search;  // a window of tens of rows: fewer starts than a whole record needs
    search.elemental_starts = std::max<int>(20, 5 * static_cast<int>(rho));
    search.lts_starts = 3;
    search.polished = 3;
    const BatchRegressionResult fit = CauchyMlRegression(Z, kept.col(0), search);
    const Eigen::VectorXd r = kept.col(0) - Z * fit.theta;
    const double gamma2 = fit.scale * fit.scale;
    IDENT_REQUIRE(gamma2 > 0, "the window is fitted exactly");
    // The residuals' robust scale; zero when more than half of the rows are fitted exactly (a window in
    // steady state), which says nothing of the noise: no start from such a window.
    const double se = MadScale(r);
    IDENT_REQUIRE(se > 0 || !strict, "more than half of the window is fitted exactly");
    const Eigen::VectorXd w = 2 / (1 + r.array().square() / gamma2);
    Eigen::MatrixXd M = Z.transpose() * w.asDiagonal() * Z / w.sum();
    M = 0.5 * (M + M.transpose());
    RequireInlierSupport(Z, w, M, strict);
    const double sigma0 = options.refine_scale && se > 0 ? growth * se : RobustScale(window.col(0));
    RegressionPrior prior;
    prior.nu0 = nu0;
    prior.V0.resize(rho + 1, rho + 1);
    prior.V0.bottomRightCorner(rho, rho) = M;
    prior.V0.bottomLeftCorner(rho, 1) = M * fit.theta;
    prior.V0.topRightCorner(1, rho) = prior.V0.bottomLeftCorner(rho, 1).transpose();
    prior.V0(0, 0) = sigma0 * sigma0 + fit.theta.dot(M * fit.theta);
    prior.Validate();
    seed = WindowInfluence(Z, r, w, gamma2, M, keep, influence);
    return prior;
  } catch (const InvalidArgument&) {
    return std::nullopt;
  }
}

// D_y(0) ← factor·D_y(0) of a prior, its centre Θ0 = V_z⁻¹V_zy kept: V_y(0) = D_y(0) + Θ0'V_zy.
void ScaleNoise(RegressionPrior& prior, double factor) {
  if (factor == 1) return;
  const Eigen::Index rho = prior.V0.rows() - 1;
  const Eigen::VectorXd vzy = prior.V0.bottomLeftCorner(rho, 1);
  const double explained = dense::Ldlt(prior.V0.bottomRightCorner(rho, rho)).solve(vzy).dot(vzy);
  prior.V0(0, 0) = factor * (prior.V0(0, 0) - explained) + explained;
}

}  // namespace

std::optional<Eigen::MatrixXd> DataScaledProvisionalV0(const Eigen::VectorXd& mean_squares) {
  if (mean_squares.size() < 2 || !((mean_squares.array() >= 1e-280).all() && (mean_squares.array() <= 1e280).all()))
    return std::nullopt;
  Eigen::VectorXd diagonal = 1e-3 * mean_squares;
  diagonal(0) = mean_squares(0);
  return Eigen::MatrixXd(diagonal.asDiagonal());
}

SafeStudentRegression::SafeStudentRegression(int num_parameters, const SafeStudentOptions& options)
    : options_(options),
      est_(std::in_place, num_parameters, Provisional(options.base, num_parameters, options.provisional_v0)),
      monitor_(DefaultMonitorWindow(options, num_parameters), options.lock_in_threshold) {
  IDENT_REQUIRE(std::isfinite(options.scale_growth) && options.scale_growth >= 1,
                "scale_growth = {}; need a finite G >= 1", options.scale_growth);
  // νβ ≈ (k+1)/(k + ê²/D_y) [spec §7a]: (k+1)/k for a sample the model fits exactly, so a threshold at or
  // above it would count every sample as low and restart every M samples.
  const double k = options.base.dof, top = (k + 1) / k;
  IDENT_REQUIRE(options.lock_in_threshold < top,
                "lock-in threshold = {}; need 0 < threshold < (k+1)/k = {} (the weight nu*beta of a sample fitted "
                "exactly)",
                options.lock_in_threshold, top);
  IDENT_REQUIRE(options.startup_window == 0 || options.startup_window >= 2,
                "startup_window = {}; need 0 (automatic) or at least 2 samples", options.startup_window);
  IDENT_REQUIRE(options.history_limit == 0 || options.history_limit >= std::max(2, monitor_.window()),
                "history_limit = {}; need 0 (keep every sample) or at least the lock-in window {}",
                options.history_limit, monitor_.window());
  IDENT_REQUIRE(options.history_reserve >= 0 && options.history_reserve <= 100'000'000,
                "history_reserve = {}; need 0 <= history_reserve <= 1e8 samples", options.history_reserve);
  if (options_.base.exact) return;
  if (!options_.base.prior)
    startup_window_ = options_.startup_window > 0 ? options_.startup_window : std::max(20, 4 * num_parameters);
  const long reserve = std::max<long>({options_.history_reserve, startup_window_, monitor_.window()});
  history_.resize(num_parameters + 1, options_.history_limit > 0 ? std::min(reserve, options_.history_limit) : reserve);
}

void SafeStudentRegression::Grow() noexcept {
  long capacity = 2 * std::max<long>(history_.cols(), 1);
  if (options_.history_limit > 0) capacity = std::min(capacity, options_.history_limit);
  history_.conservativeResize(Eigen::NoChange, capacity);
}

long SafeStudentRegression::RecentWindow() const {
  return std::min<long>(stored_, std::max(startup_window_, monitor_.window()));
}

std::optional<LockInStatus> SafeStudentRegression::lock_in() const {
  if (options_.base.exact) return std::nullopt;
  LockInStatus status{monitor_.window(),
                      monitor_.threshold(),
                      options_.restart_on_lock_in,
                      lock_ins_,
                      restarts(),
                      monitor_.low_fraction(),
                      events_};
  status.start_update = start_update_;
  status.start_window = start_window_;
  status.start_at_end = start_at_end_;
  return status;
}

void SafeStudentRegression::Replay() noexcept {
  const int rho = num_parameters();
  monitor_.Clear();
  const long first_fitted = stored_ - start_influence_.size();  // the window the start was fitted to
  for (long i = 0; i < stored_; ++i) {
    const auto sample = history_.col(Column(i));
    est_->set_outlying_regressor(Outlying(sample.tail(rho)));
    est_->set_start_influence(i >= first_fitted ? start_influence_(i - first_fitted) : 0.0);
    const StepReport r = est_->Update(sample(0), sample.tail(rho));
    if (r.updated() && i >= stored_ - monitor_.window()) monitor_.Add(r.nu * r.weight);
  }
}

bool SafeStudentRegression::FinishStartup() noexcept {
  if (!in_startup() || stored_ <= num_parameters()) return false;
  Restart(stored_, RestartKind::kStartup, /*strict=*/false);
  start_at_end_ = started_;
  return started_;
}

bool SafeStudentRegression::ReconsiderAtEnd() noexcept {
  if (options_.base.exact || in_startup() || stored_ <= num_parameters()) return false;
  return CompeteWithRobustRestart();
}

Eigen::ArrayXd SafeStudentRegression::KeptSquaredResiduals(const Eigen::VectorXd& theta) const {
  const int rho = num_parameters();
  Eigen::ArrayXd r2(stored_);
  for (long i = 0; i < stored_; ++i) {
    const auto sample = history_.col(Column(i));
    r2(i) = std::pow(sample(0) - theta.dot(sample.tail(rho)), 2);
  }
  return r2;
}

double SafeStudentRegression::ProfileNegativeLogLikelihood(
    const Eigen::VectorXd& theta, const Eigen::Array<bool, Eigen::Dynamic, 1>& left_out) const {
  const Eigen::ArrayXd all = KeptSquaredResiduals(theta);
  if (left_out.size() != all.size() || !left_out.any()) return NegativeLogLikelihood(all);
  Eigen::ArrayXd r2(all.size() - left_out.count());
  for (Eigen::Index i = 0, j = 0; i < all.size(); ++i)
    if (!left_out(i)) r2(j++) = all(i);
  return NegativeLogLikelihood(r2);
}

double SafeStudentRegression::NegativeLogLikelihood(const Eigen::ArrayXd& r2) const {
  // Student-t_k negative log-likelihood of residuals r (r2 = r²) with the scale at its maximum-likelihood
  // value (StudentScaleSquared); constants dropped.
  const double k = options_.base.dof;
  double start = std::pow(RobustScale(r2.sqrt().matrix()), 2);
  if (!(start > 0)) start = std::max(r2.mean(), 1e-300);
  const double s2 = StudentScaleSquared(r2, k, start);
  if (!(s2 > 0 && std::isfinite(s2))) return std::numeric_limits<double>::infinity();
  return 0.5 * (k + 1) * (1 + r2 / (k * s2)).log().sum() + 0.5 * static_cast<double>(r2.size()) * std::log(s2);
}

bool SafeStudentRegression::CompeteWithRobustRestart() noexcept {
  if (!options_.restart_on_lock_in || stored_ != updates_ || stored_ > kMaxCompetingSamples) return false;
  try {
    const std::size_t index = events_.size();
    std::optional<SafeStudentRegression> best;
    // Every hypothesis is judged on the same samples: the kept ones but those whose regressor carries a
    // gross output outlier (the lagged-output screen of the fit of every kept sample), which no estimate should
    // have to explain; the competitors start from the fit of the others and replay them alone (the left-out
    // ones are reported as RestartEvent::left_out).
    WindowStart fit = FitWindow(stored_, StartWeight(RestartKind::kEndOfData, stored_), /*strict=*/true);
    double best_nll = ProfileNegativeLogLikelihood(parameters(), fit.poisoned);
    SafeStudentRegression base = *this;
    if (base.LeaveOut(fit.poisoned)) LeaveOut(fit, fit.poisoned);  // the fit has left them out already
    // The samples the competitors see, oldest first (BeginPass clears the history; they are fed them again).
    Eigen::MatrixXd samples(num_parameters() + 1, base.stored_);
    for (long i = 0; i < base.stored_; ++i) samples.col(i) = base.history_.col(base.Column(i));
    // The start-up's D_y(0) carries the safety factor G^{(k+1)/k} against lock-in (spec §8); from a fit of
    // every sample the scale the fit found is a hypothesis of its own.
    const double k = options_.base.dof, safety = std::pow(options_.scale_growth, (k + 1) / k);
    const struct {
      RestartKind kind;
      double scale_factor;
    } hypotheses[] = {{RestartKind::kEndOfData, 1}, {RestartKind::kEndOfData, 1 / safety}, {RestartKind::kLockIn, 1}};
    for (const auto& h : hypotheses) {
      SafeStudentRegression candidate = base;
      WindowStart start = fit;
      if (start.prior) {
        start.prior->nu0 = StartWeight(h.kind, base.stored_);
        ScaleNoise(*start.prior, h.scale_factor);
      }
      candidate.StartFrom(std::move(start), h.kind);
      // The restart's replay weighs each sample once against the estimate of its time, as the first pass
      // did; further passes from its estimate (BeginPass) let it settle, as --passes does.
      for (int pass = 1; pass < kCompetingPasses && candidate.BeginPass(); ++pass)
        for (long i = 0; i < samples.cols(); ++i)
          candidate.Update(samples(0, i), samples.col(i).tail(num_parameters()));
      const double nll = candidate.ProfileNegativeLogLikelihood(candidate.parameters(), {});
      if (nll < best_nll) best_nll = nll, best = std::move(candidate);
    }
    if (!best) return false;
    *this = std::move(*best);
    events_[index].end_of_data = true;
    return true;
  } catch (...) {
    return false;
  }
}

void SafeStudentRegression::LeaveOut(WindowStart& start, const Eigen::Array<bool, Eigen::Dynamic, 1>& left_out) {
  const Eigen::Index n = start.window.rows(), k = n - left_out.count();
  Eigen::MatrixXd window(k, start.window.cols());
  Eigen::VectorXd influence(k);
  for (Eigen::Index i = 0, j = 0; i < n; ++i) {
    if (left_out(i)) continue;
    window.row(j) = start.window.row(i);
    influence(j++) = start.influence.size() == n ? start.influence(i) : 0.0;
  }
  start.window = std::move(window);
  if (start.influence.size() == n) start.influence = std::move(influence);
  start.poisoned = Eigen::Array<bool, Eigen::Dynamic, 1>::Constant(k, false);
}

bool SafeStudentRegression::LeaveOut(const Eigen::Array<bool, Eigen::Dynamic, 1>& left_out) {
  if (left_out.size() != stored_ || !left_out.any() || left_out.count() > stored_ - 2 * num_parameters() - 2)
    return false;
  Eigen::MatrixXd kept(history_.rows(), history_.cols());
  long k = 0;
  for (long i = 0; i < stored_; ++i)
    if (!left_out(i)) kept.col(k++) = history_.col(Column(i));
  history_ = std::move(kept);
  left_out_ += stored_ - k;
  stored_ = k;
  ring_start_ = 0;
  return true;
}

double SafeStudentRegression::StartWeight(RestartKind kind, long recent) const {
  // Start-up and end of the data: the window's fit is the prior of its samples; lock-in: ν0 = ρ+k+δ
  // pseudo-samples at the recent fit, which the replay of the older samples then outweighs.
  const StudentRegressionOptions& o = options_.base;
  return kind == RestartKind::kLockIn ? num_parameters() + o.dof + o.delta : static_cast<double>(recent);
}

SafeStudentRegression::WindowStart SafeStudentRegression::FitWindow(long recent, double nu0, bool strict) const {
  const int rho = num_parameters();
  WindowStart start;
  start.window.resize(recent, rho + 1);  // the last `recent` samples, oldest first
  for (long i = 0; i < recent; ++i) start.window.row(i) = history_.col(Column(stored_ - recent + i)).transpose();
  start.centre.resize(rho);
  start.spread.resize(rho);
  for (int j = 0; j < rho; ++j) {
    Eigen::VectorXd column = start.window.col(j + 1);
    std::nth_element(column.data(), column.data() + recent / 2, column.data() + recent);
    start.centre(j) = column(recent / 2);
    start.spread(j) = RobustScale(start.window.col(j + 1));
  }
  const double k = options_.base.dof, growth = std::pow(options_.scale_growth, (k + 1) / (2 * k));
  start.poisoned = internal::ScreenLaggedOutputs(start.window).poisoned;
  start.prior =
      RobustWindowPrior(start.window, start.poisoned, options_, nu0, growth, strict, start.influence, start.seed);
  return start;
}

void SafeStudentRegression::Restart(long recent, RestartKind kind, bool strict) noexcept {
  WindowStart start = FitWindow(recent, StartWeight(kind, recent), strict);
  if (!start.prior && kind == RestartKind::kStartup) return;  // not identifiable yet: the start-up waits
  StartFrom(std::move(start), kind);
}

void SafeStudentRegression::StartFrom(WindowStart start, RestartKind kind) noexcept {
  const int rho = num_parameters();
  const double low_before = monitor_.low_fraction();
  StudentRegressionOptions o = options_.base;
  o.leverage_guard = true;
  centre_ = std::move(start.centre);
  spread_ = std::move(start.spread);
  if (!start.prior) {
    start.prior = RegressionPrior::FromWindow(start.window, rho + o.dof + o.delta, o.delta);  // vague, equivariant
    start.influence.resize(0);
  }
  try {
    o.prior = *start.prior;
    est_ = StudentRegression(rho, o);  // assigned only if the constructor succeeds
    start_influence_ = std::move(start.influence);
    if (start_influence_.size() > 0) est_->SeedPropagatedVariance(start.seed);
  } catch (...) {
    // Not reached for a finite window (the prior is validated); the current estimator is kept.
  }
  // Every kept sample is replayed, whatever the kind; the start-up alone is not recorded as a restart.
  if (kind == RestartKind::kStartup && !started_) {
    start_update_ = updates_;
    start_window_ = start.window.rows();
  }
  started_ = true;
  Replay();
  if (kind == RestartKind::kStartup) return;
  RestartEvent event;
  event.pass = pass_;
  event.update = updates_;
  event.replayed = stored_;
  event.dropped = updates_ - stored_ - left_out_;
  event.left_out = left_out_;
  event.low_weight_before = low_before;
  event.low_weight_after = monitor_.low_fraction();
  event.resolved = !monitor_.flagged();
  events_.push_back(event);
  // A restart that did not help was not a lock-in: back off before the next one.
  backoff_ = event.resolved ? 1 : 2 * backoff_;
  next_restart_ = event.resolved ? 0 : updates_ + backoff_ * monitor_.window();
}

bool SafeStudentRegression::BeginPass() {
  if (options_.base.exact || updates_ == 0) return false;
  StudentRegressionOptions o = options_.base;
  o.leverage_guard = true;
  o.prior = RegressionPrior{static_cast<double>(updates_), est_->statistics().V()};
  // D_y(0) = the t_k scale² of the kept samples' residuals at Θ̂ (the EM fixed point s² = mean(w_i r_i²),
  // w_i = (k+1)/(k + r_i²/s²)), to which the recursion's D_y tends [spec §2], instead of a D_y still on its
  // way there from the start-up's deliberately large D_y(0). V_y(0) = D_y(0) + Θ̂'V_zΘ̂.
  if (stored_ > num_parameters()) {
    const Eigen::ArrayXd r2 = KeptSquaredResiduals(est_->parameters());
    const double s2 = StudentScaleSquared(r2, o.dof, std::pow(RobustScale(r2.sqrt().matrix()), 2));
    if (s2 > 0 && std::isfinite(s2)) o.prior->V0(0, 0) += s2 - est_->Dy();
  }
  est_ = StudentRegression(num_parameters(), o);
  est_->use_sandwich_covariance(true);  // the samples again: the estimate settles at the M-estimator's
  start_influence_.resize(0);
  stored_ = ring_start_ = updates_ = left_out_ = 0;
  next_restart_ = 0;
  backoff_ = 1;
  started_ = true;
  ++pass_;
  monitor_.Clear();
  return true;
}

void SafeStudentRegression::Reset() {
  est_ = StudentRegression(num_parameters(), Provisional(options_.base, num_parameters(), options_.provisional_v0));
  stored_ = ring_start_ = updates_ = left_out_ = 0;
  next_restart_ = 0;
  backoff_ = 1;
  started_ = false;
  lock_ins_ = 0;
  pass_ = 1;
  events_.clear();
  start_influence_.resize(0);
  start_update_ = start_window_ = 0;
  start_at_end_ = false;
  monitor_.Clear();
}

}  // namespace ident
