// Gross output outliers in a window of regression samples whose regressors carry earlier outputs (ARX: z(t)
// holds −y(t−1) … −y(t−na)), found through that errors-in-variables structure (internal to
// ident/regression/safe_student_regression.cc, whose robust starts use it).
//
// A gross outlier in y(t) also enters the regressors of the na later samples. Their rows are not outlying in
// any one coordinate when the outlier is of the size of the signal, yet they disagree with the model: fitted
// together with the clean rows, the rows of a few such outliers outweigh the rows that carry the same
// information without them, and a heavy-tailed criterion (Student-t, even Cauchy) prefers a wrong Θ — the
// outliers are then never judged gross, so nothing cleans them afterwards. The screen:
//   1. links: regressor coordinate j carries s·y of the row k earlier (s = ±1, 1 ≤ k ≤ 16) when that equality
//      holds exactly — values copied from one record are equal bit for bit — on at least 80 % of the first
//      (up to) 256 rows where it can, with at least two distinct values (a constant stretch proves nothing);
//      a link is then used at each row whose coordinate equals s·y of the row k earlier or, where rows were
//      left out in between, of a nearer one (so the screen needs no time index);
//   2. Θ_s by least trimmed squares (Rousseeuw 1984) over the rows that carry no flagged output: elemental
//      starts (ρ rows solved exactly; enough that one is free of 30 % contamination with probability
//      1 − 1e−4, at least 30, at most 500), two C-steps each, the best five refined by up to ten more
//      (Rousseeuw & Van Driessen 2006); an output is flagged when its error against the prediction is beyond kGross scales (scale: the
//      h-th smallest |residual|, h = ⌊(n+ρ+1)/2⌋), the prediction taken from a regressor whose carried outputs
//      are replaced by their predictions where those were flagged (the robust filter that
//      models/output_cleaner.h runs on a recording);
//   3. reports, per row, whether its output is flagged and whether its regressor carries a flagged output
//      (poisoned: the robust start leaves such rows out, as the workflow leaves out equations that hold a
//      cleaned output); an innovation outlier, which the next row predicts from the measured value within
//      the threshold and better than from the prediction, is not flagged. A first row whose regressor carries
//      an output from before the window, which no row of the window can judge, is poisoned when its error is
//      beyond the threshold and its own output is not flagged (a gross carried output makes it a bad
//      leverage row; an innovation there, which reads the same, has little weight in a robust fit anyway).
// Without links, or when no output is flagged, nothing is left out: data without gross output outliers, and
// static regressions, are fitted as before. Windows longer than 512 rows search for Θ_s on their last 512 and
// refine it by three C-steps on all rows. Deterministic (a fixed-seed generator). Cost O(s·m·ρ + n·ρ²) for
// s starts on m ≤ 512 rows.
#pragma once

#include <Eigen/Core>

namespace ident::internal {

struct LaggedOutputScreen {
  static constexpr double kGross = 10;  // as the cleaner's warm-up screen (models/output_cleaner.h)

  bool linked = false;                             // some regressor coordinate carries earlier outputs
  Eigen::Array<bool, Eigen::Dynamic, 1> flagged;   // the row's output is a gross error
  Eigen::Array<bool, Eigen::Dynamic, 1> poisoned;  // the row's regressor carries a flagged (or unjudged) output
};

// `window`: rows (y, z'), oldest first. Never throws for finite rows; all-false masks if nothing is found.
LaggedOutputScreen ScreenLaggedOutputs(const Eigen::Ref<const Eigen::MatrixXd>& window);

}  // namespace ident::internal
