// Property of the MODEL.json reader of `ident smooth` (workflow::ParseSmoothModel) and of the MAP
// smoother on what it accepts, on arbitrary bytes.
// Input: 1 byte nz (1..2), 1 byte T+1 (1..5), nz·(T+1) bytes of measurements z = int8/8, then the
// model's JSON text (text that is not JSON is the command's DataError path: nothing to check).
// Holds if:
//   - ParseSmoothModel throws nothing but ident::InvalidArgument;
//   - an accepted model is consistent, checked here independently of ValidateMapSmootherProblem:
//     n = cols of H[0] >= 1, every F[t] n x n, every H[t] nz x n, all entries finite, 1 or T F's,
//     1 or T+1 H's, the initial + process penalties of dimension n (1, 2 or T+1 of them), the
//     measurement penalties of dimension nz (1 or T+1);
//   - SolveMapSmoother on it throws nothing but InvalidArgument, and a converged result has finite
//     primal and dual objectives and finite states.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>

#include <nlohmann/json.hpp>

#include "common/error.h"
#include "fuzz/fuzz_util.h"
#include "ident/smoothing/map_smoother.h"
#include "ident/workflow/smoothing_model.h"

namespace ident::fuzz {

inline std::string SmoothModelProblemIsConsistent(const MapSmootherProblem& p, int nz, int T) {
  if (p.H.empty() || p.F.empty() || p.process.empty() || p.measurement.empty()) return "model has every part";
  const Eigen::Index n = p.H[0].cols();
  if (n < 1) return "state dimension >= 1";
  if (p.F.size() != 1 && static_cast<int>(p.F.size()) != T) return "1 or T F matrices";
  if (p.H.size() != 1 && static_cast<int>(p.H.size()) != T + 1) return "1 or T+1 H matrices";
  for (const auto& F : p.F)
    if (F.rows() != n || F.cols() != n || !F.allFinite()) return "every F is finite n x n";
  for (const auto& H : p.H)
    if (H.rows() != nz || H.cols() != n || !H.allFinite()) return "every H is finite nz x n";
  const std::size_t np = p.process.size();
  if (np != 1 && np != 2 && static_cast<int>(np) != T + 1) return "1, 2 or T+1 process penalties";
  for (const auto& f : p.process)
    if (f.dim() != n) return "process penalties have the state dimension";
  if (p.measurement.size() != 1 && static_cast<int>(p.measurement.size()) != T + 1)
    return "1 or T+1 measurement penalties";
  for (const auto& g : p.measurement)
    if (g.dim() != nz) return "measurement penalties have the measurement dimension";
  return {};
}

inline std::string SmoothModelProperty(const std::uint8_t* data, std::size_t size) {
  ByteReader in(data, size);
  const int nz = 1 + in.Byte() % 2;
  const int rows = 1 + in.Byte() % 5;  // T + 1
  MapSmootherProblem p;
  p.z.resize(nz, rows);
  for (int t = 0; t < rows; ++t)
    for (int i = 0; i < nz; ++i) p.z(i, t) = static_cast<std::int8_t>(in.Byte()) / 8.0;
  const std::size_t used = size - in.remaining();
  const nlohmann::json model = nlohmann::json::parse(data + used, data + size, nullptr, /*allow_exceptions=*/false);
  if (model.is_discarded()) return {};
  try {
    workflow::ParseSmoothModel(model, "model.json", &p);
  } catch (const InvalidArgument&) {
    return {};  // the expected answer to a bad model
  } catch (...) {
    return "ParseSmoothModel throws only InvalidArgument";
  }
  if (std::string bad = SmoothModelProblemIsConsistent(p, nz, rows - 1); !bad.empty()) return bad;
  try {
    const MapSmootherResult r = SolveMapSmoother(p);
    if (r.status == MapSmootherStatus::kConverged &&
        !(std::isfinite(r.primal) && std::isfinite(r.dual) && r.x.allFinite()))
      return "a converged smoother result is finite";
  } catch (const InvalidArgument&) {
    // a model the reader accepted but the solver refuses, still one clear line from `ident smooth`
  } catch (...) {
    return "SolveMapSmoother throws only InvalidArgument";
  }
  return {};
}

}  // namespace ident::fuzz
