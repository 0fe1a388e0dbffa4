// Property of the prior-file reader workflow::ReadPriorJson (the tool layer's JSON reader; the
// MODEL.json reader gets the same treatment once it lands) on arbitrary bytes.
// Input: 1 byte ρ (1..4), then the file's bytes (written to a temporary file).
// Holds if: nothing but ident::DataError is thrown, its message is one line, and a returned prior
// comes from an object with the keys nu0 and V0 only and has ν0 > 0 finite and a (ρ+1)x(ρ+1) V0 that
// factorises as symmetric positive definite.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>

#include <nlohmann/json.hpp>

#include "cli/estimator_options.h"
#include "common/error.h"
#include "fuzz/fuzz_util.h"
#include "ident/linalg/ld_factor.h"

namespace ident::fuzz {

inline std::string PriorJsonProperty(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return {};
  const int rho = 1 + data[0] % 4;
  static const ScratchDir dir("ident-prior-fuzz-");
  static const std::string path = dir.path() + "/prior.json";
  if (std::FILE* f = std::fopen(path.c_str(), "wb")) {
    std::fwrite(data + 1, 1, size - 1, f);
    std::fclose(f);
  } else {
    return {};  // cannot write the temporary file: nothing to test
  }
  try {
    const RegressionPrior prior = workflow::ReadPriorJson(path, rho);
    const auto j = nlohmann::json::parse(data + 1, data + size, nullptr, /*allow_exceptions=*/false);
    if (!j.is_object() || j.size() != 2) return "a prior file holds the keys nu0 and V0 only";
    if (!(std::isfinite(prior.nu0) && prior.nu0 > 0)) return "nu0 is positive and finite";
    if (prior.V0.rows() != rho + 1 || prior.V0.cols() != rho + 1) return "V0 has the model's size";
    try {
      LdFactor<> check(prior.V0);
    } catch (const InvalidArgument&) {
      return "V0 is symmetric positive definite";
    }
  } catch (const DataError& e) {
    // the expected answer to a bad file: one line naming it
    if (std::string(e.what()).find_first_of("\r\n") != std::string::npos) return "a message is one line";
  }
  return {};
}

}  // namespace ident::fuzz
