#include "ident/workflow/compare.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <exception>
#include <mutex>
#include <numeric>
#include <random>
#include <thread>

#include <fmt/format.h>

#include "common/error.h"
#include "ident/workflow/internal/fit_steps.h"

namespace ident::workflow {
namespace {

// The exact update sequence an estimator was given (it depends on the estimator when regressor cleaning
// is on), kept to replay it for timing.
struct Recording {
  Eigen::VectorXd y;
  Eigen::MatrixXd z;
  Eigen::Index count = 0;

  // Nanoseconds per update of `fresh` over the recorded sequence and the read-out of its estimate: the
  // median over 7 timed blocks, each of whole passes lasting at least 1 ms.
  double TimeReplay(AnyRegressionEstimator& fresh) const {
    if (count == 0) return 0;
    using Clock = std::chrono::steady_clock;
    double checksum = 0;
    std::vector<double> blocks;
    for (int block = 0; block < 7; ++block) {
      long updates = 0;
      const auto start = Clock::now();
      do {
        fresh.Reset();
        for (Eigen::Index i = 0; i < count; ++i) checksum += fresh.Update(y(i), z.col(i)).weight;
        checksum += fresh.parameters()(0);  // a batch estimator solves here: its time is part of the fit
        updates += count;
      } while (Clock::now() - start < std::chrono::milliseconds(1));
      blocks.push_back(std::chrono::duration<double, std::nano>(Clock::now() - start).count() /
                       static_cast<double>(updates));
    }
    if (checksum == -1) fmt::print(stderr, " ");  // keep the loop observable
    std::nth_element(blocks.begin(), blocks.begin() + 3, blocks.end());
    return blocks[3];
  }
};

// Forwards to an estimator and records every (y, z) it was given into a Recording.
class RecordingEstimator final : public AnyRegressionEstimator {
 public:
  RecordingEstimator(AnyRegressionEstimator& inner, int capacity, Recording& out) : inner_(inner), out_(out) {
    out_.y.resize(capacity);
    out_.z.resize(inner.num_parameters(), capacity);
    out_.count = 0;
  }
  std::string name() const override { return inner_.name(); }
  StepReport Update(double y, const Eigen::Ref<const Eigen::VectorXd>& z) override {
    if (out_.count < out_.y.size()) {
      out_.y(out_.count) = y;
      out_.z.col(out_.count) = z;
      ++out_.count;
    }
    return inner_.Update(y, z);
  }
  int num_parameters() const override { return inner_.num_parameters(); }
  Eigen::VectorXd parameters() const override { return inner_.parameters(); }
  Eigen::MatrixXd covariance() const override { return inner_.covariance(); }
  double Predict(const Eigen::Ref<const Eigen::VectorXd>& z) const override { return inner_.Predict(z); }
  double nu() const override { return inner_.nu(); }
  double Dy() const override { return inner_.Dy(); }
  double noise_std() const override { return inner_.noise_std(); }
  void Reset() override { inner_.Reset(); }
  std::optional<LockInStatus> lock_in() const override { return inner_.lock_in(); }
  bool judges_outliers() const override { return inner_.judges_outliers(); }
  std::string kind() const override { return inner_.kind(); }
  bool BeginPass() override {
    out_.count = 0;  // the timed replay is of the last pass
    return inner_.BeginPass();
  }
  bool in_startup() const override { return inner_.in_startup(); }
  bool FinishStartup() override { return inner_.FinishStartup(); }
  bool ReconsiderAtEnd() override { return inner_.ReconsiderAtEnd(); }

 private:
  AnyRegressionEstimator& inner_;
  Recording& out_;
};

constexpr int kTimedTrials = 5;  // time per update: median over the first trials

}  // namespace

OutlierSpec OutlierSpec::Parse(const std::string& text) {
  OutlierSpec spec;
  if (text == "none") {
    spec.rate = 0;
    return spec;
  }
  std::vector<std::string> parts;
  for (std::size_t start = 0;;) {
    const std::size_t colon = text.find(':', start);
    parts.push_back(text.substr(start, colon - start));
    if (colon == std::string::npos) break;
    start = colon + 1;
  }
  IDENT_REQUIRE(parts.size() == 2 || parts.size() == 3,
                "--outliers '{}': need RATE:SIZE[:SEED], e.g. 0.05:20 or 0.05:20:7", text);
  auto number = [&text](const std::string& s, const char* what) {
    std::size_t used = 0;
    double v = std::nan("");
    try {
      v = std::stod(s, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    IDENT_REQUIRE(used == s.size() && !s.empty() && std::isfinite(v), "--outliers '{}': {} '{}' is not a number", text,
                  what, s);
    return v;
  };
  spec.rate = number(parts[0], "RATE");
  spec.size = number(parts[1], "SIZE");
  IDENT_REQUIRE(spec.rate >= 0 && spec.rate < 1, "--outliers '{}': RATE = {}; need 0 <= RATE < 1", text, spec.rate);
  IDENT_REQUIRE(spec.size >= 0, "--outliers '{}': SIZE = {}; need SIZE >= 0", text, spec.size);
  if (parts.size() == 3) {
    const double seed = number(parts[2], "SEED");
    IDENT_REQUIRE(seed >= 0 && seed == std::floor(seed) && seed < 9.007e15,
                  "--outliers '{}': SEED = {}; need a non-negative integer", text, parts[2]);
    spec.seed = static_cast<std::uint64_t>(seed);
  }
  return spec;
}

std::string OutlierSpec::ToString() const { return fmt::format("{}:{}:{}", rate, size, seed); }

std::vector<int> InjectOutliers(Eigen::Ref<Eigen::VectorXd> y, Segment segment, double rate, double amplitude,
                                std::uint64_t seed) {
  IDENT_REQUIRE(rate >= 0 && rate < 1, "outlier rate = {}; need 0 <= rate < 1", rate);
  IDENT_REQUIRE(std::isfinite(amplitude) && amplitude >= 0, "outlier amplitude = {}; need a finite value >= 0",
                amplitude);
  IDENT_REQUIRE(segment.first >= 0 && segment.count >= 0 && segment.first + segment.count <= y.size(),
                "segment [{}, {}) is outside the {} samples", segment.first, segment.first + segment.count, y.size());
  const int count = static_cast<int>(std::floor(rate * segment.count + 0.5));
  std::vector<int> index(static_cast<std::size_t>(segment.count));
  std::iota(index.begin(), index.end(), 0);
  std::mt19937_64 rng(seed);
  std::vector<int> rows;
  for (int i = 0; i < count; ++i) {
    const auto m = static_cast<std::uint64_t>(segment.count - i);
    std::swap(index[static_cast<std::size_t>(i)], index[static_cast<std::size_t>(i + static_cast<int>(rng() % m))]);
    const double sign = (rng() & 1) ? 1.0 : -1.0;
    const int row = segment.first + index[static_cast<std::size_t>(i)];
    y(row) += sign * amplitude;
    rows.push_back(row);
  }
  std::sort(rows.begin(), rows.end());
  return rows;
}

Spread Spread::Of(std::vector<double> v) {
  Spread s;
  if (v.empty()) {  // no value (every trial failed): NaN throughout
    s.mean = s.std = s.min = s.median = s.p90 = s.max = std::numeric_limits<double>::quiet_NaN();
    return s;
  }
  std::sort(v.begin(), v.end());
  const double n = static_cast<double>(v.size());
  s.mean = std::accumulate(v.begin(), v.end(), 0.0) / n;
  double ss = 0;
  for (double x : v) ss += (x - s.mean) * (x - s.mean);
  s.std = v.size() > 1 ? std::sqrt(ss / (n - 1)) : 0.0;
  s.min = v.front();
  s.max = v.back();
  const std::size_t h = v.size() / 2;
  s.median = v.size() % 2 ? v[h] : 0.5 * (v[h - 1] + v[h]);
  const double position = 0.9 * (n - 1);
  const std::size_t below = static_cast<std::size_t>(std::floor(position));
  const std::size_t above = std::min(below + 1, v.size() - 1);
  s.p90 = v[below] + (position - static_cast<double>(below)) * (v[above] - v[below]);
  return s;
}

namespace {

// The estimators' settings with their default priors in the data's own scale (UseDataScaledPrior,
// ident/registry/estimator_registry.h) from the clean estimation part's mean squares, the clean least-squares
// reference's settings, and the fit options every trial uses.
struct TrialSettings {
  std::vector<EstimatorSettings> estimators;
  EstimatorSettings least_squares;
  FitOptions fit;
};

TrialSettings ScaledSettings(const io::DataTable& data, Segment estimation, DataSource& source,
                             const std::vector<EstimatorSettings>& estimators, const FitOptions& options) {
  TrialSettings t{estimators, {}, options};
  const Eigen::VectorXd mean_squares = EstimationMeanSquares(data, estimation, source);
  if ((t.least_squares.prior = DataScaledDefaultPrior(t.least_squares, mean_squares))) {
    for (auto& s : t.estimators) UseDataScaledPrior(s, mean_squares);
    bool absolute_prior = false;  // an --exact estimator keeps the unit-free flat prior and its check
    for (const auto& s : t.estimators) absolute_prior = absolute_prior || (!s.prior && s.exact);
    if (!absolute_prior) t.fit.min_regressor_information = 0;
  }
  t.fit.trace = nullptr;
  t.fit.on_update = {};
  return t;
}

// One estimator on one corrupted record, scored on the clean data.
struct TrialRun {
  std::string failure;  // why the estimate is unusable; "" if usable
  std::string kind;
  int passes = 1;
  Eigen::VectorXd theta;
  FitScores scores;
  double distance = 0, cleaned = 0;
  double offset = 0;    // CorruptedOutputOffset
  Recording recording;  // the update sequence (kept for the timed trials)
};

// One estimator's results over the trials, added in trial order (so that any number of threads gives the
// same sums).
struct Tally {
  std::vector<double> one_step, simulation, distance, ns, cleaned, one_step_per_trial, distance_per_trial;
  Eigen::VectorXd theta_sum;
  double offset_sum = 0;
  std::string kind, failure;
  int passes = 1, failed = 0;

  Tally(int rho, int trials)
      : one_step_per_trial(static_cast<std::size_t>(trials), std::nan("")),
        distance_per_trial(static_cast<std::size_t>(trials), std::nan("")) {
    theta_sum = Eigen::VectorXd::Zero(rho);
  }

  void Add(const TrialRun& run, int trial) {
    kind = run.kind;
    passes = run.passes;
    offset_sum += run.offset;
    if (!run.failure.empty()) {
      if (failed++ == 0) failure = fmt::format("trial {}: {}", trial + 1, run.failure);
      return;
    }
    cleaned.push_back(run.cleaned);
    theta_sum += run.theta;
    one_step.push_back(run.scores.one_step);
    one_step_per_trial[static_cast<std::size_t>(trial)] = run.scores.one_step;
    if (run.scores.simulation) simulation.push_back(*run.scores.simulation);
    distance.push_back(run.distance);
    distance_per_trial[static_cast<std::size_t>(trial)] = run.distance;
  }

  EstimatorScore Summary(const std::string& label, int trials, double output_mean) const {
    EstimatorScore score;
    score.output_offset = output_mean + offset_sum / trials;
    score.estimator = label;
    score.kind = kind;
    score.passes = passes;
    const int succeeded = trials - failed;
    score.theta = succeeded > 0 ? Eigen::VectorXd(theta_sum / succeeded)
                                : Eigen::VectorXd::Constant(theta_sum.size(), std::numeric_limits<double>::quiet_NaN());
    score.failed_trials = failed;
    score.failure = failure;
    score.one_step = Spread::Of(one_step);
    score.one_step_per_trial = one_step_per_trial;
    score.theta_distance_per_trial = distance_per_trial;
    score.has_simulation = !simulation.empty();
    score.simulation = Spread::Of(simulation);
    score.theta_distance = Spread::Of(distance);
    score.ns_per_update =
        ns.empty() ? std::numeric_limits<double>::quiet_NaN() : Spread::Of(ns).median;  // of the timed trials' medians
    score.cleaned = Spread::Of(cleaned).mean;
    return score;
  }
};

// The output's detrending offset that `ident fit` would subtract from the corrupted record, in the
// coordinates of the clean record's detrending (0 without detrending): the mean of the corrupted estimation
// outputs, or for a robust estimator on a dynamic structure their mean after the Hampel filter.
double CorruptedOutputOffset(const io::DataTable& corrupted, const DataSource& source,
                             const EstimatorSettings& settings, const FitOptions& fit, Segment estimation) {
  if (fit.detrend != Detrend::kMean) return 0;
  FitOptions own = fit;
  own.robust_offset = RegressionEstimatorTraits(settings.name).robust;
  const int c = source.output_column();
  const std::string& name = corrupted.names[static_cast<std::size_t>(c)];
  const auto y = corrupted.values.col(c).segment(estimation.first, estimation.count);
  if (internal::RobustOffsetColumn(own, source) == c) return internal::RobustOffset(y, corrupted.source, name);
  internal::RunningMean mean;
  for (Eigen::Index r = 0; r < y.size(); ++r) mean.Add(y(r));
  return mean.Get(corrupted.source, name);
}

// Runs one estimator on one corrupted record, detrended as `ident fit` detrends it for that estimator, and
// scores the model (θ with that operating point) on the clean `data`.
TrialRun RunTrial(const io::DataTable& data, const io::DataTable& corrupted_record, DataSource& source,
                  const EstimatorSettings& settings, const FitOptions& fit, const CompareResult& result) {
  TrialRun run;
  const double offset = CorruptedOutputOffset(corrupted_record, source, settings, fit, result.estimation);
  run.offset = offset;
  io::DataTable corrupted = corrupted_record, clean = data;
  corrupted.values.col(source.output_column()).array() -= offset;
  clean.values.col(source.output_column()).array() -= offset;
  auto estimator = MakeRegressionEstimator(settings, source.num_parameters());
  run.kind = estimator->kind();
  RecordingEstimator recorder(*estimator, result.estimation.count, run.recording);
  // One estimator's failure on one trial is that estimator's result, reported beside the others.
  try {
    const int updates = Estimate(corrupted, result.estimation, source, recorder, fit, &run.passes).first;
    run.failure = UnusableResult(*estimator, result.parameter_names, updates);
  } catch (const DataError& error) {
    run.failure = error.what();
  } catch (const InvalidArgument& error) {
    run.failure = error.what();
  }
  if (!run.failure.empty()) return run;
  run.cleaned = static_cast<double>(source.cleaned());
  run.theta = estimator->parameters();
  // Scored on the uncorrupted record: with split = 1 the validation rows are the estimation rows,
  // whose corrupted outputs would reward the estimator that fits the outliers.
  run.scores = Score(clean, result.validation, source, run.theta);
  run.distance = (run.theta - result.theta_ls).norm() / result.theta_ls.norm();
  return run;
}

// Every (trial, estimator) run, trials spread over `jobs` threads (each with its own copy of the data
// source); runs[trial][estimator]. Rethrows the first unexpected exception of a thread.
std::vector<std::vector<TrialRun>> RunTrials(const io::DataTable& data, const DataSource& source,
                                             const TrialSettings& settings, CompareResult& result,
                                             const CompareOptions& options) {
  const std::size_t estimators = settings.estimators.size();
  std::vector<std::vector<TrialRun>> runs(static_cast<std::size_t>(options.trials));
  std::atomic<int> next{0};
  std::mutex progress_mutex;
  int done = 0;
  const int total = options.trials * static_cast<int>(estimators);
  std::vector<std::exception_ptr> errors(static_cast<std::size_t>(std::max(1, options.jobs)));
  auto work = [&](std::size_t worker) {
    try {
      const std::unique_ptr<DataSource> local = source.Clone();
      for (int trial = next++; trial < options.trials; trial = next++) {
        io::DataTable corrupted = data;
        const std::vector<int> rows = InjectOutliers(corrupted.values.col(local->output_column()), result.estimation,
                                                     options.outliers.rate, options.outliers.size * result.sigma,
                                                     options.outliers.seed + static_cast<std::uint64_t>(trial));
        std::vector<TrialRun>& row = runs[static_cast<std::size_t>(trial)];
        for (std::size_t e = 0; e < estimators; ++e) {
          row.push_back(RunTrial(data, corrupted, *local, settings.estimators[e], settings.fit, result));
          if (trial >= kTimedTrials) row.back().recording = {};
          if (options.progress) {
            const std::lock_guard<std::mutex> lock(progress_mutex);
            options.progress(++done, total);
          }
        }
        if (trial == 0) result.outliers_per_trial = static_cast<int>(rows.size());
      }
    } catch (...) {
      errors[worker] = std::current_exception();
      next = options.trials;  // the other threads stop after their current trial
    }
  };
  const int jobs = std::clamp(options.jobs, 1, options.trials);
  std::vector<std::thread> threads;
  for (int j = 1; j < jobs; ++j) threads.emplace_back(work, static_cast<std::size_t>(j));
  work(0);
  for (std::thread& t : threads) t.join();
  for (const std::exception_ptr& error : errors)
    if (error) std::rethrow_exception(error);
  return runs;
}

}  // namespace

CompareResult Compare(io::DataTable data, DataSource& source, const std::vector<EstimatorSettings>& estimators,
                      const std::vector<std::string>& labels, const CompareOptions& options) {
  IDENT_REQUIRE(!estimators.empty(), "--estimators: give at least one estimator");
  IDENT_REQUIRE(labels.size() == estimators.size(), "{} labels for {} estimators", labels.size(), estimators.size());
  IDENT_REQUIRE(options.trials >= 1 && options.trials <= 100000, "--trials = {}; need 1 <= trials <= 100000",
                options.trials);
  const int rho = source.num_parameters();
  for (const auto& s : estimators) MakeRegressionEstimator(s, rho);  // fail fast on a bad name/option

  CompareResult result;
  result.experiments = TableExperiments(data);
  std::vector<std::pair<int, double>> means;
  std::tie(result.estimation, result.validation) = PrepareData(data, source, options.fit, &means);
  for (const auto& [column, mean] : means)
    if (column == source.output_column()) result.output_mean = mean;
  result.structure = source.structure();
  result.parameter_names = source.parameter_names();
  const TrialSettings settings = ScaledSettings(data, result.estimation, source, estimators, options.fit);

  // Clean-data least squares: reference θ, σ and scores.
  auto ls = MakeRegressionEstimator(settings.least_squares, rho);
  Estimate(data, result.estimation, source, *ls, settings.fit);
  result.theta_ls = ls->parameters();
  result.sigma = ls->noise_std();
  result.reference = Score(data, result.validation, source, result.theta_ls);
  IDENT_REQUIRE(std::isfinite(result.sigma), "{}: the clean least-squares fit has no residual std (too few samples)",
                data.source);

  const std::vector<std::vector<TrialRun>> runs = RunTrials(data, source, settings, result, options);
  std::vector<Tally> tallies(estimators.size(), Tally(rho, options.trials));
  for (int trial = 0; trial < options.trials; ++trial) {
    for (std::size_t e = 0; e < estimators.size(); ++e) {
      const TrialRun& run = runs[static_cast<std::size_t>(trial)][e];
      tallies[e].Add(run, trial);
      // Timed one at a time after the runs, so that other threads do not disturb the timing.
      if (trial < kTimedTrials && run.failure.empty()) {
        auto fresh = MakeRegressionEstimator(settings.estimators[e], rho);
        tallies[e].ns.push_back(run.recording.TimeReplay(*fresh));
      }
    }
  }
  bool any = false;
  for (std::size_t e = 0; e < estimators.size(); ++e) {
    result.scores.push_back(tallies[e].Summary(labels[e], options.trials, result.output_mean));
    any = any || tallies[e].failed < options.trials;
  }
  if (!any)
    throw DataError(
        fmt::format("{}: every estimator failed on every trial ({}, {})", data.source, labels[0], tallies[0].failure));
  auto key = [](const EstimatorScore& s) { return std::isnan(s.one_step.mean) ? -HUGE_VAL : s.one_step.mean; };
  std::stable_sort(result.scores.begin(), result.scores.end(),
                   [&key](const EstimatorScore& a, const EstimatorScore& b) { return key(a) > key(b); });
  return result;
}

}  // namespace ident::workflow
