// The interior-point iteration of the MAP smoother's fast path (internal to
// ident/smoothing/internal/map_smoother_fast_path.cc; see map_smoother_fast_path.h): the solver's state, its start,
// the stopping rule, the predictor-corrector step and the finish. The passes over the step records are defined in
// map_smoother_fast_path_passes.h, the step records and their kernels in map_smoother_fast_path_steps.h.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <new>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include "common/dense_decompositions.h"
#include "common/error.h"
#include "ident/linalg/internal/simd_clones.h"
#include "ident/linalg/work_arena.h"
#include "ident/smoothing/internal/fork_join.h"
#include "ident/smoothing/internal/map_smoother_fast_path_steps.h"
#include "ident/smoothing/internal/map_smoother_result.h"
#include "ident/smoothing/map_smoother.h"

namespace ident::internal::fast_path {

using models::Penalty;
using models::PlqForm;

// MapSmootherOptions::threads = 0: a second thread from this many time steps on, where a pass over half the
// record takes far longer than handing it to the worker.
constexpr int kParallelMinSteps = 1024;

// The step records take huge pages only up to this many bytes, about a last-level cache (WorkArena): every pass
// streams them in order, and beyond the cache it runs as fast on 4 KiB pages, whose first touch costs less on
// virtual machines (bench/compare_cvxopt.py times T = 10^5 and 10^6).
constexpr std::size_t kStepRecordsHugePageLimit = std::size_t{32} << 20;

template <int kN>
class FastSolver {
 public:
  FastSolver(const MapSmootherProblem& p, const MapSmootherOptions& o)
      : p_(p),
        o_(o),
        T_(p.T()),
        fork_(o.threads >= 2 || (o.threads == 0 && p.T() + 1 >= kParallelMinSteps)),
        sigma_(MapSmootherDataUnit(p)),
        z_(p.z.row(0).transpose() / sigma_) {
    invariant_ = p.F.size() == 1 && p.H.size() == 1 && p.process.size() <= 2 && p.measurement.size() == 1;
    // Bound-free process penalties: W = B'K^-1 B and c0 = p - B'K^-1 b, once per distinct penalty.
    std::vector<const Penalty*> seen;
    for (int t = 0; t <= T_ && (t < 2 || !invariant_); ++t) {
      const Penalty* f = &p.ft(t);
      if (std::find(seen.begin(), seen.end(), f) != seen.end()) continue;
      seen.push_back(f);
      const PlqForm& q = f->plq();
      const Eigen::LLT<Eigen::MatrixXd> llt = dense::Llt(q.M);
      IDENT_REQUIRE(llt.info() == Eigen::Success, "{} penalty: M must be positive definite without bounds", f->Name());
      const Eigen::MatrixXd KinvB = llt.solve(q.B);
      process_.push_back({f, q.B.transpose() * KinvB, (q.p - KinvB.transpose() * q.b) / sigma_});  // in the unit σ
    }
    const int num_constants = invariant_ ? std::min(T_ + 1, 3) : T_ + 1;
    constants_.resize(num_constants);
    for (int t = 0; t <= T_; ++t) {
      const int i = ConstantIndex(t);
      if (t == 0 || !invariant_ || (i == 1 && t == 1) || t == T_)
        FillStepConstants<kN>(p, t, Process(t).W, Process(t).c0, t < T_ ? &Process(t + 1).W : nullptr, sigma_,
                              &constants_[i]);
    }
    const std::size_t N = T_ + 1;
    const std::size_t state_doubles = (sizeof(StepState<kN>) + sizeof(double) - 1) / sizeof(double);
    arena_ = std::make_unique<WorkArena>(WorkArena::Padded(N * state_doubles) + WorkArena::Padded(N * kN),
                                         kStepRecordsHugePageLimit);
    steps_ = reinterpret_cast<StepState<kN>*>(arena_->Take(N * state_doubles));
    x_ = arena_->Take(N * kN);
    // The records' first writes, split between the two threads as the passes are: at large T the first touch
    // of fresh pages (the kernel's zeroing, and in a virtual machine the host's faults) takes as long as
    // several passes.
    const int m = Middle();
    double top_scale = 0, bottom_scale = 0;
    fork_.Run([&] { top_scale = StartSteps(0, m); }, [&] { bottom_scale = StartSteps(m, T_ + 1); });
    bound_scale_ = std::max({bound_scale_, top_scale, bottom_scale});
    for (const auto& F : p.F) matrix_scale_ = std::max(matrix_scale_, 1 + F.cwiseAbs().maxCoeff());
    for (const auto& H : p.H) matrix_scale_ = std::max(matrix_scale_, 1 + H.cwiseAbs().maxCoeff());
    for (const ProcessPenalty& f : process_) weight_scale_ = std::max(weight_scale_, f.W.cwiseAbs().maxCoeff());
  }

  MapSmootherResult Run() {
    MapSmootherResult res;
    const double z_scale = 1 + z_.cwiseAbs().maxCoeff();
    const double num_constraints = 2.0 * (T_ + 1);
    res.status = MapSmootherStatus::kMaxIterations;
    int iter = 0;
    double mu = 0, alpha = 0, mu_scale = 1;  // mu_scale: the general path's
    std::vector<double> history;             // KKT residual per iteration (stall test)
    history.reserve(static_cast<std::size_t>(o_.max_iterations) + 1);
    for (;; ++iter) {
      bool factored = false;  // the Newton matrix of the new iterate, factored in the same pass
      const Residuals r = StepResidualsAndFactor(alpha, &factored);
      mu = r.complementarity / num_constraints;
      if (iter == 0) mu_scale = std::max(1.0, mu);
      double r4_floor = 0;
      const double kkt = KktResidual(r, z_scale, num_constraints, &r4_floor);
      res.kkt_residual = kkt;
      history.push_back(kkt);
      if (o_.on_iteration) o_.on_iteration(iter, kkt);
      if (Stops(iter, kkt, r, r4_floor, z_scale, history, &res)) break;
      if (!factored) {  // as the general path: accept a breakdown at the precision limit
        res.status =
            kkt <= 1e3 * o_.tolerance * mu_scale ? MapSmootherStatus::kConverged : MapSmootherStatus::kNumericalFailure;
        break;
      }
      alpha = PredictorCorrector(r.complementarity, mu, num_constraints);
    }
    res.iterations = iter;
    Finish(z_scale, mu, &res);
    return res;
  }

 private:
  struct ProcessPenalty {
    const Penalty* penalty;
    Eigen::MatrixXd W;
    Eigen::VectorXd c0;
  };
  struct Residuals {
    double complementarity = 0, r3max = 0, r4max = 0, v_scale = 1, umax = 0, xmax = 0, objective_scale = 0, qmax = 0;
  };
  struct Backward {
    double max_step = std::numeric_limits<double>::infinity();
    double max_ratio = 0;       // max -d/v over the components of s, q: the step limit is 1 / max_ratio
    double sum1 = 0, sum2 = 0;  // sum s.*dq + q.*ds, sum ds.*dq (complementarity after a step)
  };

  // R4's round-off floor (into *r4_floor) and the relative KKT residual: the general path's.
  double KktResidual(const Residuals& r, double z_scale, double num_constraints, double* r4_floor) const {
    *r4_floor = kFloorFactor * std::numeric_limits<double>::epsilon() * matrix_scale_ *
                (weight_scale_ * matrix_scale_ * (r.xmax + z_scale) + r.v_scale);
    return RelativeKktResidual(
        r.complementarity, r.objective_scale, num_constraints,
        r.r3max / std::max(1 + r.qmax, kResidualFloorFactor * std::numeric_limits<double>::epsilon() *
                                           (z_scale * matrix_scale_ + bound_scale_ + r.qmax) / o_.tolerance),
        r.r4max / std::max(r.v_scale * matrix_scale_, *r4_floor / o_.tolerance));
  }

  // The stopping rule before a Newton step (the general path's): converged, out of iterations, stalled, or
  // diverging multipliers; sets res's status and message and returns true if the iteration stops.
  bool Stops(int iter, double kkt, const Residuals& r, double r4_floor, double z_scale,
             const std::vector<double>& history, MapSmootherResult* res) const {
    if (StopsOnProgress(o_, iter, kkt, history, r4_floor / (r.v_scale * matrix_scale_), sigma_ * r.xmax, res))
      return true;
    if (r.umax > 1e10 * bound_scale_ * z_scale) {
      int t = 0;
      for (int s = 0; s <= T_; ++s)
        if (std::abs(steps_[s].u) > std::abs(steps_[t].u)) t = s;
      MarkDiverging(sigma_ * r.umax, t, r.umax / (bound_scale_ * z_scale), res);
      return true;
    }
    return false;
  }

  // Mehrotra predictor-corrector on the factored Newton matrix: affine direction, centring
  // sigma = (mu_aff / mu)^3, then the corrected direction with the second-order term ds_aff .* dq_aff.
  // Returns the step length of the corrected direction (applied by the next StepAndResiduals).
  double PredictorCorrector(double complementarity, double mu, double num_constraints) {
    const Backward affine = BackwardAndRecover(0.0, false);
    const double alpha_aff = std::min(1.0, affine.max_step);
    const double mu_aff = (complementarity + alpha_aff * (affine.sum1 + alpha_aff * affine.sum2)) / num_constraints;
    const double sigma = std::pow(std::clamp(mu_aff / mu, 0.0, 1.0), 3);
    CorrectorForward(sigma * mu);
    const Backward corrected = BackwardAndRecover(sigma * mu, true);
    return std::min(1.0, o_.step_fraction * corrected.max_step);
  }

  // The states and multipliers back in the data's unit, and the dual values and Newton weights of the
  // iterate for the certificate's dual polish: the process duals c0 + W r and their W, the measurement's
  // K^-1 = 1 / (m + q_lo/s_lo + q_hi/s_hi); then the common finish, with the step records released first
  // (they are most of the memory, and the finish allocates its own arrays).
  void Finish(double z_scale, double mu, MapSmootherResult* res) {
    res->x = sigma_ * Eigen::Map<const Eigen::MatrixXd>(x_, kN, T_ + 1);
    res->u.resize(1, T_ + 1);
    MapSmootherDualIterate dual;
    dual.process_dual.resize(kN, T_ + 1);
    // Time-invariant: one weight column per process penalty (ProcessWeightColumn).
    const int weight_columns = invariant_ ? std::min(static_cast<int>(p_.process.size()), T_ + 1) : T_ + 1;
    dual.process_weight.resize(kN * kN, weight_columns);
    dual.measurement_weight.resize(1, T_ + 1);
    const int m = Middle();  // the passes' split: steps t < m, then t >= m
    fork_.Run([&] { FinishSteps(0, m, weight_columns, &dual, res); },
              [&] { FinishSteps(m, T_ + 1, weight_columns, &dual, res); });
    steps_ = nullptr;
    x_ = nullptr;
    arena_.reset();
    FinishMapSmootherResult(p_, o_, sigma_ * z_scale, mu, &dual, res, &fork_);
  }

  // Steps [begin, end) of Finish: u, the process duals and the Newton weights, back in the data's unit.
  void FinishSteps(int begin, int end, int weight_columns, MapSmootherDualIterate* dual_out,
                   MapSmootherResult* res) const {
    MapSmootherDualIterate& dual = *dual_out;
    for (int t = begin; t < end; ++t) {
      const StepConstants<kN>& c = Constants(t);
      const StepState<kN>& s = steps_[t];
      res->u(0, t) = sigma_ * s.u;  // p + B'u = u (identity B, p = 0)
      const double* xt = x_ + t * kN;
      double w[kN];
      for (int i = 0; i < kN; ++i) w[i] = xt[i];
      if (t > 0)
        for (int j = 0; j < kN; ++j)
          for (int i = 0; i < kN; ++i) w[i] -= c.F[i + j * kN] * xt[j - kN];
      for (int i = 0; i < kN; ++i) {
        double v = c.c0[i];
        for (int j = 0; j < kN; ++j) v += c.W[i + j * kN] * w[j];
        dual.process_dual(i, t) = sigma_ * v;
      }
      if (t < weight_columns || !invariant_)
        for (int i = 0; i < kN * kN; ++i) dual.process_weight(i, ProcessWeightColumn(dual.process_weight, t)) = c.W[i];
      dual.measurement_weight(0, t) = 1.0 / (c.m + s.qlo / s.slo + s.qhi / s.shi);
    }
  }

  // Steps [begin, end) of the starting point: x = 0 and u, s, q strictly interior with C'u + s = c exactly (as
  // the general path). Returns the largest |bound| among them.
  double StartSteps(int begin, int end) {
    double scale = 0;
    for (int t = begin; t < end; ++t) {
      const StepConstants<kN>& c = Constants(t);
      StepState<kN>& s = *new (&steps_[t]) StepState<kN>{};
      s.u = 0.5 * (c.lo + c.hi);
      s.slo = s.u - c.lo;
      s.shi = c.hi - s.u;
      s.qlo = s.qhi = 1.0;
      for (int i = 0; i < kN; ++i) x_[t * kN + i] = 0.0;  // written, not read, first: no zero page to copy
      scale = std::max({scale, std::abs(c.lo), std::abs(c.hi)});
    }
    return scale;
  }

  int ConstantIndex(int t) const {
    if (!invariant_) return t;
    return t == 0 ? 0 : t == T_ ? std::min(T_, 2) : 1;
  }

  const ProcessPenalty& Process(int t) const {
    const Penalty* f = &p_.ft(t);
    for (const ProcessPenalty& q : process_)
      if (q.penalty == f) return q;
    return process_.front();  // not reached: every f_t was prepared
  }

  const StepConstants<kN>& Constants(int t) const { return constants_[ConstantIndex(t)]; }

  // The passes over the step records (map_smoother_fast_path_passes.h).
  [[gnu::always_inline]] inline void ApplyStep(int t, double alpha, bool with_x);
  [[gnu::always_inline]] inline double StepResidual(int t, const double* x, const double* xp, double* vd, double* R4o,
                                                    Residuals* out) const;
  [[gnu::always_inline]] inline void CompleteR4(int t, const double* vd_next, double* R4, Residuals* out) const;
  Residuals StepResidualsAndFactor(double alpha, bool* factored);
  static Residuals Combine(const Residuals& a, const Residuals& b);
  IDENT_SIMD_CLONES Residuals TopForward(double alpha, bool* factored);
  IDENT_SIMD_CLONES Residuals BottomForward(double alpha, double* vd_below, bool* factored);
  [[gnu::always_inline]] inline bool FactorStep(int t, const double* R4, double r3, bool from_above, bool from_below,
                                                double* carry, double* v_carry);
  void CorrectorForward(double target);
  IDENT_SIMD_CLONES void CorrectorHalf(double target, int from, int to, int dir, double* last);
  [[gnu::always_inline]] inline void CorrectorStep(double target, int t, const double* dva, const double* dwb,
                                                   double* dv_out);
  Backward BackwardAndRecover(double target, bool corrector);
  IDENT_SIMD_CLONES void BackwardHalf(double target, bool corrector, int from, int to, Backward* result);
  [[gnu::always_inline]] inline void Recover(int t, const double* dx, double target, bool corrector, Backward* out);

  int Middle() const { return T_ / 2; }

  const MapSmootherProblem& p_;
  const MapSmootherOptions& o_;
  const int T_;
  ForkJoin fork_;           // the halves of each pass on two threads, or one after the other
  bool invariant_ = false;  // one F, one H, f_0 and one f, one g: three step-constant records
  std::vector<ProcessPenalty> process_;
  std::vector<StepConstants<kN>> constants_;
  std::unique_ptr<WorkArena> arena_;
  StepState<kN>* steps_ = nullptr;
  double* x_ = nullptr;      // kN x (T+1)
  const double sigma_;       // the data unit (MapSmootherDataUnit)
  const Eigen::VectorXd z_;  // the measurements in that unit
  double bound_scale_ = 1, matrix_scale_ = 1;
  double weight_scale_ = 0;  // max |W| of the process penalties (R4's round-off floor)
};

}  // namespace ident::internal::fast_path
