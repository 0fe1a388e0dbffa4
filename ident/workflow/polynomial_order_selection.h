// Order selection over ARMAX, output-error and Box–Jenkins structures (MATLAB's struc/selstruc for
// polynomial models), and over any grid (ARX too) fitted by a robust estimator: every structure of a grid of
// (na, nb, nk, nc, nd, nf) fitted by its recursive estimator (ident/workflow/fit_record.h: pseudo-linear
// regression or RPEM, `passes` passes over the estimation part), then scored on the same rows.
//
// Unlike ARX, these models have no order-recursive least-squares solution: each structure is one fit,
// O(passes·N·ρ²). The loss V is the mean square of the one-step residuals ε(t) = y(t) − ŷ(t|t−1) of the
// final θ over the estimation rows t ≥ T0, T0 the largest first regression row of the grid, so that every
// structure is scored on the same samples; the criteria are those of ident/workflow/order_selection.h with
// d = na + nb + nc + nd + nf parameters. Combinations that are no model (an A polynomial with F, D
// without F) are left out.
//
// With the estimator cauchy or student:k the structures are scored by the Student-t_k likelihood of the same
// residuals, the scale γ profiled out (ident/workflow/student_likelihood.h), counting d + 1 parameters:
//   AIC = 2 NLL + 2(d+1),  BIC = 2 NLL + (d+1) log N,  MDL = BIC/2,
//   validation = NLL_k of the validation residuals at the estimation γ;
// FPE, a least-squares criterion, is refused (and NaN in the scores). `loss` stays the mean square. Each
// structure is fitted as FitRecord fits it (for ARX with cauchy/student: with its output cleaning); the
// residuals are those of the final θ on the measured outputs.
#pragma once

#include <functional>
#include <optional>
#include <string>

#include "ident/io/csv.h"
#include "ident/workflow/fit_record.h"
#include "ident/workflow/order_selection.h"

namespace ident::workflow {

struct PolynomialOrderGrid {
  OrderGrid arx;
  int nc_min = 0, nc_max = 0;
  int nd_min = 0, nd_max = 0;
  int nf_min = 0, nf_max = 0;
};

// The Student-t dof k that scores a grid fitted by `estimator`: nullopt for rls (least squares), 1 for
// cauchy, k for student:k / student with dof. Throws InvalidArgument for another estimator or a missing k.
std::optional<double> OrderCriterionDof(const EstimatorSpec& estimator);

// `request` gives the output, input, recursion, estimator, split, passes and detrending; its orders are
// replaced by each structure's. `name` names the record in messages. Throws InvalidArgument for a bad grid or
// criterion, or when no combination of the grid is a model.
// `progress`, if set, is told (done, total, "structures") after each fit.
OrderSelection SelectPolynomialOrders(
    const io::DataTable& table, const std::string& name, const PolynomialOrderGrid& grid, FitRequest request,
    const std::string& criterion, const std::function<void(long done, long total, const char* unit)>& progress = {});

}  // namespace ident::workflow
