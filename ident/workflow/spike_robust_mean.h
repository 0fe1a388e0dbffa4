// The detrending offset of a recorded output for the robust estimators: its mean after a Hampel filter
// (Pearson, "Outliers in process modeling and identification", IEEE Trans. Control Syst. Technol. 10(1),
// 2002), so that isolated gross errors in y do not move the operating point the model is fitted around.
//
// A model without an intercept, fitted to y − m, absorbs an error δ in m as a constant term
// −(1 + a1 + … + a_na)·δ in every equation. With the plain mean, K additive outliers of size s in N
// samples give δ = (Σ signs)·s/N: it grows with s, so the larger the outliers the larger the bias, while
// the robust weight of each outlier itself falls with s. The filter removes that path:
//   r(t) = median of the finite y(t−4) … y(t+4) (the window cut at the ends of the record),
//   d(t) = y(t) − r(t),  S = 1.4826 · median of the nonzero |d(t)|  (the MAD scale of the deviations;
//          exact zeros, as of a quantised signal on a plateau, carry no scale),
//   y(t) is flagged when |d(t)| > kSpikeThreshold · S; flagged samples leave the windows and the rest are
//   judged again by the medians of what is left, until no new sample is flagged (a cluster of spikes that
//   fills half a window hides from the first median, not once its edges are out);
//   the offset is the mean of y with each flagged y(t) replaced by the median of its window's kept samples.
// Level changes and steps pass the median unchanged, so a signal without spikes keeps its plain mean up to
// the few samples beyond the threshold. NaN (missing) samples are skipped throughout.
// Cost O(N) time per round (a few rounds), O(N) memory.
#pragma once

#include <Eigen/Core>

namespace ident::workflow {

// Deviations beyond this many MAD scales count as spikes: the output cleaner's gross-error threshold
// (models/output_cleaner.h, --clean-gross).
inline constexpr double kSpikeThreshold = 5;

// The offset above of y; 0 when y has no finite value.
double SpikeRobustMean(const Eigen::Ref<const Eigen::VectorXd>& y);

}  // namespace ident::workflow
