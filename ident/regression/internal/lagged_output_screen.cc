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

constexpr long kProbeRows = 256, kMaxLag = 16, kSearchRows = 512;
constexpr int kRefined = 5, kMaxCSteps = 10, kRefineSteps = 3;
constexpr double kInf = std::numeric_limits<double>::infinity();

// Rows [first, first + n) of a window as plain arrays (the screen's loops run on these): y_i and z_i, row-major.
struct Rows {
  Rows(const Eigen::Ref<const Eigen::MatrixXd>& w, long first, long count)
      : n(count),
        rho(static_cast<int>(w.cols() - 1)),
        y(static_cast<std::size_t>(count)),
        z(static_cast<std::size_t>(count * rho)) {
    for (long i = 0; i < n; ++i) {
      y[static_cast<std::size_t>(i)] = w(first + i, 0);
      for (int j = 0; j < rho; ++j) z[static_cast<std::size_t>(i * rho + j)] = w(first + i, j + 1);
    }
  }
  const double* Z(long i) const { return z.data() + i * rho; }
  double Predict(long i, const double* theta) const {
    const double* zi = Z(i);
    double s = 0;
    for (int j = 0; j < rho; ++j) s += zi[j] * theta[j];
    return s;
  }

  long n;
  int rho;
  std::vector<double> y, z;
};

// Regressor coordinate `column` (0-based in z) of a row carries sign·y of the row `lag` earlier.
struct Link {
  int column;
  long lag;
  double sign;
};

// The row whose output row i carries through link l: the row l.lag earlier, or a nearer one where rows in
// between were left out; −1 if none.
long Source(const Rows& r, long i, const Link& l) {
  const double v = r.Z(i)[l.column];
  for (long p = std::max(0L, i - l.lag); p < i; ++p)
    if (v == l.sign * r.y[static_cast<std::size_t>(p)]) return p;
  return -1;
}

// The link of one coordinate, if the first rows show one (see the header, step 1).
std::optional<Link> FindLink(const Rows& r, int column) {
  const long n = std::min(r.n, kProbeRows);
  for (long lag = 1; lag <= std::min(kMaxLag, n / 2); ++lag) {
    for (const double sign : {-1.0, 1.0}) {
      long count = 0;
      double lo = kInf, hi = -kInf;
      for (long i = lag; i < n; ++i) {
        const double source = r.y[static_cast<std::size_t>(i - lag)];
        if (r.Z(i)[column] != sign * source) continue;
        ++count;
        lo = std::min(lo, source);
        hi = std::max(hi, source);
      }
      if (static_cast<double>(count) >= 0.8 * static_cast<double>(n - lag) && lo < hi) return Link{column, lag, sign};
    }
  }
  return std::nullopt;
}

// The robust filter at Θ: an output whose error is beyond `threshold` is flagged and stored as its prediction,
// which later rows that carry it use in its place (those rows are poisoned) — unless the first row that carries
// it is predicted from the measured value within the threshold, and better than from the prediction: then it
// was an innovation, which the dynamics carry on, and it is unflagged (the cleaner's test, models/output_cleaner.h
// Restore). A row whose regressor carries an output from before the first row cannot have that output judged:
// if its error is beyond the threshold and its own output is not flagged in the end, it is poisoned too (a gross
// carried output makes it a bad leverage row; an innovation there, which reads the same, has little weight in a
// robust fit anyway).
struct Filtered {
  std::vector<char> flagged, poisoned;
  std::vector<double> stored;
  std::vector<char> gross_carrying_earlier;  // error beyond the threshold, carries an output from before row 0
};
void Filter(const Rows& r, const std::vector<Link>& links, const double* theta, double threshold, Filtered& f) {
  for (long i = 0; i < r.n; ++i) {
    const double y = r.y[static_cast<std::size_t>(i)], measured = r.Predict(i, theta);
    double cleaned = measured;
    bool carries = false, carries_earlier = false;
    for (const Link& l : links) {
      const long p = Source(r, i, l);
      carries_earlier = carries_earlier || (p < 0 && i < l.lag);
      if (p < 0 || !f.flagged[static_cast<std::size_t>(p)]) continue;
      cleaned += theta[l.column] * (l.sign * f.stored[static_cast<std::size_t>(p)] - r.Z(i)[l.column]);
      carries = true;
    }
    double prediction = cleaned;
    const double e_measured = std::abs(y - measured);
    if (carries && e_measured <= threshold && e_measured <= std::abs(y - cleaned)) {
      for (const Link& l : links) {
        const long p = Source(r, i, l);
        if (p < 0 || !f.flagged[static_cast<std::size_t>(p)]) continue;
        f.flagged[static_cast<std::size_t>(p)] = 0;
        f.stored[static_cast<std::size_t>(p)] = r.y[static_cast<std::size_t>(p)];
      }
      carries = false;
      prediction = measured;
    }
    const auto k = static_cast<std::size_t>(i);
    f.poisoned[k] = carries;
    f.flagged[k] = std::abs(y - prediction) > threshold;
    f.gross_carrying_earlier[k] = carries_earlier && f.flagged[k];
    f.stored[k] = f.flagged[k] ? prediction : y;
  }
  for (std::size_t k = 0; k < f.flagged.size(); ++k)
    if (f.gross_carrying_earlier[k] && !f.flagged[k]) f.poisoned[k] = 1;
}

std::optional<Eigen::VectorXd> Finite(Eigen::VectorXd theta) {
  if (!theta.allFinite()) return std::nullopt;
  return theta;
}

// Θ's fit of one set of rows: residuals, the filter's masks, the LTS objective over the rows that carry no
// flagged output (the sum of the h smallest squared residuals; +inf with fewer than h such rows). The
// workspaces are sized once.
class Fit {
 public:
  Fit(const Rows& rows, const std::vector<Link>& links)
      : r_(rows),
        links_(links),
        h_((rows.n + rows.rho + 1) / 2),
        f_{std::vector<char>(static_cast<std::size_t>(rows.n)), std::vector<char>(static_cast<std::size_t>(rows.n)),
           std::vector<double>(static_cast<std::size_t>(rows.n)), std::vector<char>(static_cast<std::size_t>(rows.n))},
        residual_(static_cast<std::size_t>(rows.n)),
        work_(static_cast<std::size_t>(rows.n)) {
    selected_.reserve(static_cast<std::size_t>(rows.n));
  }

  double Objective(const Eigen::VectorXd& theta) {
    double* e = residual_.data();
    double* a = work_.data();
    for (long i = 0; i < r_.n; ++i)
      e[i] = r_.y[static_cast<std::size_t>(i)] - r_.Predict(i, theta.data()), a[i] = std::abs(e[i]);
    std::nth_element(a, a + h_ - 1, a + r_.n);
    const double scale = a[h_ - 1];
    Filter(r_, links_, theta.data(), scale > 0 ? LaggedOutputScreen::kGross * scale : kInf, f_);
    long m = 0;
    for (long i = 0; i < r_.n; ++i)
      if (!f_.poisoned[static_cast<std::size_t>(i)]) a[m++] = e[i] * e[i];
    if (m < h_) return kInf;
    std::nth_element(a, a + h_ - 1, a + m);
    double q = 0;
    for (long i = 0; i < h_; ++i) q += a[i];
    return std::isfinite(q) ? q : kInf;
  }

  // After Objective(Θ): least squares on the h rows that carry no flagged output with the smallest |r|.
  std::optional<Eigen::VectorXd> CStep() {
    selected_.clear();
    for (long i = 0; i < r_.n; ++i)
      if (!f_.poisoned[static_cast<std::size_t>(i)]) selected_.push_back(i);
    if (static_cast<long>(selected_.size()) < h_) return std::nullopt;
    const double* e = residual_.data();
    std::nth_element(selected_.begin(), selected_.begin() + h_ - 1, selected_.end(),
                     [e](long a, long b) { return std::abs(e[a]) < std::abs(e[b]); });
    const int rho = r_.rho;
    std::vector<double> A(static_cast<std::size_t>(rho * rho), 0.0), b(static_cast<std::size_t>(rho), 0.0);
    for (long k = 0; k < h_; ++k) {  // the normal equations of the h rows (lower triangle)
      const long i = selected_[static_cast<std::size_t>(k)];
      const double* zi = r_.Z(i);
      const double yi = r_.y[static_cast<std::size_t>(i)];
      for (int c = 0; c < rho; ++c) {
        b[static_cast<std::size_t>(c)] += yi * zi[c];
        for (int d = c; d < rho; ++d) A[static_cast<std::size_t>(c * rho + d)] += zi[c] * zi[d];
      }
    }
    const Eigen::MatrixXd normal = Eigen::Map<const Eigen::MatrixXd>(A.data(), rho, rho);  // column-major: lower
    const Eigen::LLT<Eigen::MatrixXd> llt = dense::Llt(normal);
    if (llt.info() != Eigen::Success) return std::nullopt;
    return Finite(llt.solve(Eigen::Map<const Eigen::VectorXd>(b.data(), rho)));
  }

  // The Θ that fits ρ rows exactly; nothing if they do not determine it.
  std::optional<Eigen::VectorXd> Elemental(const long* rows) const {
    const int rho = r_.rho;
    Eigen::MatrixXd Z(rho, rho);
    Eigen::VectorXd y(rho);
    for (int k = 0; k < rho; ++k) {
      for (int j = 0; j < rho; ++j) Z(k, j) = r_.Z(rows[k])[j];
      y(k) = r_.y[static_cast<std::size_t>(rows[k])];
    }
    const Eigen::FullPivLU<Eigen::MatrixXd> lu = dense::FullPivLu(Z);
    if (!lu.isInvertible()) return std::nullopt;
    return Finite(lu.solve(y));
  }

  // C-steps from Θ while the objective falls (at most `steps`); returns the objective reached and leaves the
  // masks of the Θ returned.
  double Descend(Eigen::VectorXd& theta, int steps) {
    double q = Objective(theta);
    for (int s = 0; s < steps && q < kInf; ++s) {
      const std::optional<Eigen::VectorXd> next = CStep();
      if (!next) break;
      const double q_next = Objective(*next);
      if (!(q_next < q)) {
        Objective(theta);  // the masks back to Θ's
        break;
      }
      theta = *next, q = q_next;
    }
    return q;
  }

  Mask Flagged() const { return ToMask(f_.flagged); }
  Mask Poisoned() const { return ToMask(f_.poisoned); }

 private:
  static Mask ToMask(const std::vector<char>& v) {
    Mask m(static_cast<Eigen::Index>(v.size()));
    for (std::size_t i = 0; i < v.size(); ++i) m(static_cast<Eigen::Index>(i)) = v[i] != 0;
    return m;
  }

  const Rows& r_;
  const std::vector<Link>& links_;
  long h_;
  Filtered f_;
  std::vector<double> residual_, work_;
  std::vector<long> selected_;
};

struct Candidate {
  Eigen::VectorXd theta;
  double objective = kInf;
};

// Elemental starts, two C-steps each, the best kRefined to convergence (see the header, step 2).
std::optional<Eigen::VectorXd> Search(const Rows& rows, const std::vector<Link>& links) {
  const long n = rows.n;
  const int rho = rows.rho;
  Fit fit(rows, links);
  // Enough elemental starts that one is free of a 30 % contamination with probability 1 − 1e−4.
  const int starts = std::clamp(
      static_cast<int>(std::ceil(std::log(1e-4) / std::log1p(-std::pow(0.7, static_cast<double>(rho))))), 30, 500);
  std::mt19937_64 rng(0x5eed1a99);
  std::vector<long> index(static_cast<std::size_t>(n));
  std::iota(index.begin(), index.end(), 0L);
  std::vector<Candidate> candidates;
  for (int s = 0; s < starts; ++s) {
    for (long i = 0; i < rho; ++i)  // a partial Fisher–Yates shuffle: ρ distinct rows
      std::swap(index[static_cast<std::size_t>(i)],
                index[static_cast<std::size_t>(i + static_cast<long>(rng() % static_cast<std::uint64_t>(n - i)))]);
    std::optional<Eigen::VectorXd> theta = fit.Elemental(index.data());
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
  const long n = window.rows();
  const int rho = static_cast<int>(window.cols() - 1);
  LaggedOutputScreen screen;
  screen.flagged = Mask::Constant(n, false);
  screen.poisoned = Mask::Constant(n, false);
  if (rho < 1 || n < 2 * rho + 2 || !window.allFinite()) return screen;
  const Rows all(window, 0, n);
  std::vector<Link> links;
  for (int j = 0; j < rho; ++j)
    if (const std::optional<Link> l = FindLink(all, j)) links.push_back(*l);
  if (links.empty()) return screen;
  screen.linked = true;
  const long searched = std::min(n, kSearchRows);
  std::optional<Eigen::VectorXd> theta =
      searched == n ? Search(all, links) : Search(Rows(window, n - searched, searched), links);
  if (!theta) return screen;
  Fit fit(all, links);
  if (!(fit.Descend(*theta, n > kSearchRows ? kRefineSteps : 0) < kInf)) return screen;
  screen.flagged = fit.Flagged();
  screen.poisoned = fit.Poisoned();
  return screen;
}

}  // namespace ident::internal
