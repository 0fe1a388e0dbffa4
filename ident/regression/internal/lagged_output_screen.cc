#include "ident/regression/internal/lagged_output_screen.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <optional>
#include <random>
#include <vector>

#include "common/dense_decompositions.h"

namespace ident::internal {
namespace {

using Mask = Eigen::Array<bool, Eigen::Dynamic, 1>;
using Window = Eigen::Ref<const Eigen::MatrixXd>;

constexpr Eigen::Index kProbeRows = 256, kMaxLag = 16, kSearchRows = 512;
constexpr int kRefined = 10, kMaxCSteps = 20, kRefineSteps = 3;
constexpr double kInf = std::numeric_limits<double>::infinity();

// Regressor coordinate `column` of a row carries sign·y of the row `lag` earlier.
struct Link {
  Eigen::Index column;
  Eigen::Index lag;
  double sign;
};

bool Carries(const Window& w, Eigen::Index i, const Link& l) {
  return i >= l.lag && w(i, l.column) == l.sign * w(i - l.lag, 0);
}

// The row whose output row i carries through link l: the row l.lag earlier, or a nearer one where rows in
// between were left out; −1 if none.
Eigen::Index Source(const Window& w, Eigen::Index i, const Link& l) {
  for (Eigen::Index p = std::max<Eigen::Index>(0, i - l.lag); p < i; ++p)
    if (w(i, l.column) == l.sign * w(p, 0)) return p;
  return -1;
}

// The link of one coordinate, if the first rows show one (see the header, step 1).
std::optional<Link> FindLink(const Window& w, Eigen::Index column) {
  const Eigen::Index n = std::min(w.rows(), kProbeRows);
  for (Eigen::Index lag = 1; lag <= std::min(kMaxLag, n / 2); ++lag) {
    for (const double sign : {-1.0, 1.0}) {
      const Link l{column, lag, sign};
      Eigen::Index count = 0;
      double lo = kInf, hi = -kInf;
      for (Eigen::Index i = lag; i < n; ++i) {
        if (!Carries(w, i, l)) continue;
        ++count;
        lo = std::min(lo, w(i - lag, 0));
        hi = std::max(hi, w(i - lag, 0));
      }
      if (static_cast<double>(count) >= 0.8 * static_cast<double>(n - lag) && lo < hi) return l;
    }
  }
  return std::nullopt;
}

// The robust filter at Θ: an output whose error is beyond `threshold` is flagged and stored as its prediction,
// which later rows that carry it use in its place (those rows are poisoned) — unless the first row that carries
// it is predicted from the measured value within the threshold, and better than from the prediction: then it
// was an innovation, which the dynamics carry on, and it is unflagged (the cleaner's test, models/output_cleaner.h
// Restore). `stored`: workspace of n.
void Filter(const Window& w, const std::vector<Link>& links, const Eigen::VectorXd& theta, double threshold,
            Mask& flagged, Mask& poisoned, Eigen::VectorXd& stored) {
  const Eigen::Index rho = w.cols() - 1;
  for (Eigen::Index i = 0; i < w.rows(); ++i) {
    const double measured = w.row(i).tail(rho).transpose().dot(theta);
    double cleaned = measured;
    bool carries = false;
    for (const Link& l : links) {
      const Eigen::Index p = Source(w, i, l);
      if (p < 0 || !flagged(p)) continue;
      cleaned += theta(l.column - 1) * (l.sign * stored(p) - w(i, l.column));
      carries = true;
    }
    double prediction = cleaned;
    const double e_measured = std::abs(w(i, 0) - measured);
    if (carries && e_measured <= threshold && e_measured <= std::abs(w(i, 0) - cleaned)) {
      for (const Link& l : links)
        if (const Eigen::Index p = Source(w, i, l); p >= 0 && flagged(p)) flagged(p) = false, stored(p) = w(p, 0);
      carries = false;
      prediction = measured;
    }
    poisoned(i) = carries;
    flagged(i) = std::abs(w(i, 0) - prediction) > threshold;
    stored(i) = flagged(i) ? prediction : w(i, 0);
  }
}

// Θ's fit of one window: residuals, the filter's masks, the LTS objective over the rows that carry no flagged
// output (the sum of the h smallest squared residuals; +inf with fewer than h such rows).
class Fit {
 public:
  Fit(const Window& w, const std::vector<Link>& links)
      : w_(w),
        links_(links),
        h_((w.rows() + w.cols()) / 2),
        flagged_(w.rows()),
        poisoned_(w.rows()),
        stored_(w.rows()),
        r_(w.rows()) {}

  double Objective(const Eigen::VectorXd& theta) {
    r_ = w_.col(0) - w_.rightCols(w_.cols() - 1) * theta;
    Eigen::VectorXd a = r_.cwiseAbs();
    std::nth_element(a.data(), a.data() + h_ - 1, a.data() + a.size());
    const double scale = a(h_ - 1);
    Filter(w_, links_, theta, scale > 0 ? LaggedOutputScreen::kGross * scale : kInf, flagged_, poisoned_, stored_);
    std::vector<double> squares;
    for (Eigen::Index i = 0; i < r_.size(); ++i)
      if (!poisoned_(i)) squares.push_back(r_(i) * r_(i));
    if (static_cast<Eigen::Index>(squares.size()) < h_) return kInf;
    std::nth_element(squares.begin(), squares.begin() + h_ - 1, squares.end());
    const double q = std::accumulate(squares.begin(), squares.begin() + h_, 0.0);
    return std::isfinite(q) ? q : kInf;
  }

  // After Objective(Θ): least squares on the h rows that carry no flagged output with the smallest |r|.
  std::optional<Eigen::VectorXd> CStep() const {
    std::vector<Eigen::Index> rows;
    for (Eigen::Index i = 0; i < r_.size(); ++i)
      if (!poisoned_(i)) rows.push_back(i);
    if (static_cast<Eigen::Index>(rows.size()) < h_) return std::nullopt;
    std::nth_element(rows.begin(), rows.begin() + h_ - 1, rows.end(),
                     [&](Eigen::Index a, Eigen::Index b) { return std::abs(r_(a)) < std::abs(r_(b)); });
    return Solve(std::vector<Eigen::Index>(rows.begin(), rows.begin() + h_));
  }

  // Least squares on `rows` (exact for ρ rows); nothing if they do not determine Θ.
  std::optional<Eigen::VectorXd> Solve(const std::vector<Eigen::Index>& rows) const {
    const Eigen::Index rho = w_.cols() - 1;
    Eigen::MatrixXd Z(static_cast<Eigen::Index>(rows.size()), rho);
    Eigen::VectorXd y(Z.rows());
    for (Eigen::Index k = 0; k < Z.rows(); ++k) {
      Z.row(k) = w_.row(rows[static_cast<std::size_t>(k)]).tail(rho);
      y(k) = w_(rows[static_cast<std::size_t>(k)], 0);
    }
    const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr = dense::ColPivQr(Z);
    if (qr.rank() < rho) return std::nullopt;
    Eigen::VectorXd theta = qr.solve(y);
    if (!theta.allFinite()) return std::nullopt;
    return theta;
  }

  // C-steps from Θ while the objective falls (at most `steps`); returns the objective reached.
  double Descend(Eigen::VectorXd& theta, int steps) {
    double q = Objective(theta);
    for (int s = 0; s < steps && q < kInf; ++s) {
      const std::optional<Eigen::VectorXd> next = CStep();
      if (!next) break;
      const double q_next = Objective(*next);
      if (!(q_next < q)) break;
      theta = *next, q = q_next;
    }
    Objective(theta);  // the masks of Θ
    return q;
  }

  const Mask& flagged() const { return flagged_; }
  const Mask& poisoned() const { return poisoned_; }

 private:
  const Window& w_;
  const std::vector<Link>& links_;
  Eigen::Index h_;
  Mask flagged_, poisoned_;
  Eigen::VectorXd stored_, r_;
};

struct Candidate {
  Eigen::VectorXd theta;
  double objective = kInf;
};

// Elemental starts, two C-steps each, the best kRefined to convergence (see the header, step 2).
std::optional<Eigen::VectorXd> Search(const Window& w, const std::vector<Link>& links) {
  const Eigen::Index n = w.rows(), rho = w.cols() - 1;
  Fit fit(w, links);
  const int starts = std::clamp(30 * static_cast<int>(rho), 100, 500);
  std::mt19937_64 rng(0x5eed1a99);
  std::vector<Eigen::Index> index(static_cast<std::size_t>(n));
  std::iota(index.begin(), index.end(), 0);
  std::vector<Candidate> candidates;
  for (int s = 0; s < starts; ++s) {
    for (Eigen::Index i = 0; i < rho; ++i)  // a partial Fisher–Yates shuffle: ρ distinct rows
      std::swap(
          index[static_cast<std::size_t>(i)],
          index[static_cast<std::size_t>(i + static_cast<Eigen::Index>(rng() % static_cast<std::uint64_t>(n - i)))]);
    std::optional<Eigen::VectorXd> theta = fit.Solve(std::vector<Eigen::Index>(index.begin(), index.begin() + rho));
    if (!theta) continue;
    const double q = fit.Descend(*theta, 2);
    if (q < kInf) candidates.push_back({std::move(*theta), q});
  }
  if (candidates.empty()) return std::nullopt;
  const auto refined = candidates.begin() + std::min<std::ptrdiff_t>(kRefined, std::ssize(candidates));
  std::partial_sort(candidates.begin(), refined, candidates.end(),
                    [](const Candidate& a, const Candidate& b) { return a.objective < b.objective; });
  Candidate best;
  for (auto c = candidates.begin(); c != refined; ++c) {
    c->objective = fit.Descend(c->theta, kMaxCSteps);
    if (c->objective < best.objective) best = *c;
  }
  if (!(best.objective < kInf)) return std::nullopt;
  return best.theta;
}

}  // namespace

LaggedOutputScreen ScreenLaggedOutputs(const Eigen::Ref<const Eigen::MatrixXd>& window) {
  const Eigen::Index n = window.rows(), rho = window.cols() - 1;
  LaggedOutputScreen screen;
  screen.flagged = Mask::Constant(n, false);
  screen.poisoned = Mask::Constant(n, false);
  if (rho < 1 || n < 2 * rho + 2 || !window.allFinite()) return screen;
  std::vector<Link> links;
  for (Eigen::Index j = 1; j <= rho; ++j)
    if (const std::optional<Link> l = FindLink(window, j)) links.push_back(*l);
  if (links.empty()) return screen;
  screen.linked = true;
  std::optional<Eigen::VectorXd> theta = Search(window.bottomRows(std::min(n, kSearchRows)), links);
  if (!theta) return screen;
  Fit all(window, links);
  if (!(all.Descend(*theta, n > kSearchRows ? kRefineSteps : 0) < kInf)) return screen;
  screen.flagged = all.flagged();
  screen.poisoned = all.poisoned();
  return screen;
}

}  // namespace ident::internal
