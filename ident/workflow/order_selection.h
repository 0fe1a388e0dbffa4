// ARX order and delay selection (MATLAB's arxstruc/selstruc): the least-squares loss and the information
// criteria of every ARX(na, nb, nk) of a grid, one output and one input.
//
// All structures are fitted on the same samples, the rows t ≥ T0 = max(na_max, nk_max + nb_max − 1) of the
// estimation part whose lagged values are all finite, so that their losses compare; in a table of several
// experiments (io::DataTable::experiment_starts) also the first T0 rows of each experiment only fill the lags,
// so that no w(t) straddles two experiments. The data enter once:
// the Gram matrix G = Σ_t w(t) w(t)' of w(t) = [y(t), −y(t−1) … −y(t−na_max), u(t−nk_min) … u(t−nk_max−nb_max+1)]
// holds every structure's normal equations as a sub-block (the lags of a structure are a subset of w's), and
// each structure then costs one Cholesky solve of its ρ×ρ block:
//   θ = G_zz⁻¹ G_zy,  loss V = (G_yy − G_zy'θ)/N   (the mean square of the one-step residuals).
// Criteria with d = na + nb parameters over N samples (Ljung, System Identification, 2nd ed., §16.4):
//   AIC = N log V + 2d,  BIC = N log V + d log N,  FPE = V (1 + d/N)/(1 − d/N),  MDL = V (1 + d log N / N),
//   validation = the mean square of the one-step residuals on the validation part (rows t ≥ T0 of it),
//                from its own Gram matrix H: (H_yy − 2θ'H_zy + θ'H_zz θ)/N_v.
// Cost: O(N m²) for G and H (m = 1 + na_max + nb_max + nk_max − nk_min), then O(ρ³) per structure.
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "ident/io/csv.h"
#include "ident/workflow/fit.h"

namespace ident::workflow {

struct OrderGrid {
  int na_min = 1, na_max = 5;
  int nb_min = 1, nb_max = 5;
  int nk_min = 1, nk_max = 1;
  // Parses "A:B" or "A" (one value). Throws InvalidArgument naming `option`.
  static std::pair<int, int> ParseRange(const std::string& text, const std::string& option);
};

struct StructureScore {
  int na = 0, nb = 0, nk = 0;
  int nc = 0, nd = 0, nf = 0;  // ARMAX/OE/BJ (ident/workflow/polynomial_order_selection.h); 0 for ARX
  int n_parameters = 0;
  double loss = 0;  // mean square of the one-step residuals over the estimation samples
  double aic = 0, bic = 0, fpe = 0, mdl = 0;
  std::optional<double> validation_loss;  // with a validation part
  // Scored by a Student-t_k likelihood (robust estimators, ident/workflow/student_likelihood.h): the NLL of
  // the estimation residuals at the profiled scale γ, γ, and the validation residuals' NLL at that γ.
  // aic, bic and mdl are then likelihood-based and fpe is NaN (polynomial_order_selection.h).
  std::optional<double> nll, scale, validation_nll;
  Eigen::VectorXd theta;
};

struct OrderSelection {
  int samples = 0;                         // N, estimation samples every structure is fitted on
  int validation_samples = 0;              // scored validation samples (0 without a validation part)
  std::string criterion;                   // the one the structures are sorted by
  std::vector<StructureScore> structures;  // best first
  // ARMAX/OE/BJ grids: the structures whose fit was unusable (an unstable predictor, …), with the reason.
  std::vector<std::pair<StructureScore, std::string>> left_out;
};

// "aic", "bic", "fpe", "mdl" or "validation" (needs split < 1). `output` and `input` are column indices of
// the prepared (split and detrended) table. Throws InvalidArgument for a bad grid or criterion, too few
// samples, or regressors that do not determine a structure (a singular block). `progress`, if set, is told
// (done, total, unit) as the rows ("rows") and then the structures ("structures") are worked through.
OrderSelection SelectOrders(const io::DataTable& prepared, Segment estimation, Segment validation, int output,
                            int input, const OrderGrid& grid, const std::string& criterion,
                            const std::function<void(long done, long total, const char* unit)>& progress = {});

// The value of `criterion` for one structure (lower is better); "validation" is validation_nll when the
// structure has an nll, else validation_loss.
double CriterionValue(const StructureScore& s, const std::string& criterion);

}  // namespace ident::workflow
