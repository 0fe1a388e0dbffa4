// Reading a MAP-smoothing model (ident smooth MODEL.json DATA.csv) into an ident::MapSmootherProblem.
//
// MODEL.json:
//   {
//     "F": [[1, 1], [0, 1]],                 // n x n, or an array of T matrices (time-varying)
//     "H": [[1, 1]],                         // nz x n, or an array of T+1 matrices
//     "initial": {"penalty": "quadratic", "covariance": [[1, 0], [0, 1]]},   // on w_0 = x_0
//     "process": {"penalty": "quadratic", "covariance": 1},                  // on w_t, or T penalties
//     "measurement": {"penalty": "l1"}                                      // on z_t - H_t x_t, or T+1
//   }
// Penalties: quadratic (covariance: matrix, or a number c meaning c I; value 1/2 r'C^-1 r), l1,
// huber (kappa), vapnik (epsilon), quantile (tau), piecewise_linear (knots, values; +inf outside),
// box (lower, upper: arrays with null for -inf/+inf; M: matrix or number) = sup_{lower<=u<=upper} r'u - u'Mu/2.
// DATA.csv: column z (nz = 1) or z1, z2, ... (one per measurement); T+1 rows.
//
// Every problem throws InvalidArgument naming the file and the JSON path ("model.json: process.kappa ...").
#pragma once

#include <string>

#include <nlohmann/json.hpp>

#include "ident/io/csv.h"
#include "ident/smoothing/map_smoother.h"

namespace ident::workflow {

// Fills F, H and the penalties from `model`; z (nz x (T+1)) must already be set in `problem`.
void ParseSmoothModel(const nlohmann::json& model, const std::string& source, MapSmootherProblem* problem);
models::Penalty ParsePenalty(const nlohmann::json& j, int dim, const std::string& where);

// Reads MODEL.json and DATA.csv into a validated problem. Throws DataError / InvalidArgument.
MapSmootherProblem ReadSmoothProblem(const std::string& model_path, const std::string& data_path,
                                     const io::CsvOptions& csv = {});

}  // namespace ident::workflow
