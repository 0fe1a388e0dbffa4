// Test data of the bad-input tests: the bundled dryer.csv record with every u and y multiplied by a
// factor (values near overflow: 1e300), written to the test's temporary directory.
#pragma once

#include <string>

#include <fmt/format.h>

#include "tests/support/cli.h"
#include "tests/support/test_data.h"

namespace ident::testing {

// Writes dryer.csv with u multiplied by `u_scale` and y by `y_scale` (printed with 17 digits) as `name`;
// returns its path.
inline std::string ScaledDryer(const std::string& name, double u_scale, double y_scale) {
  const std::string text = ReadFile(DatasetPath("dryer.csv"));
  std::string out = text.substr(0, text.find('\n') + 1);
  std::size_t pos = out.size();
  while (pos < text.size()) {
    const std::size_t end = text.find('\n', pos);
    const std::string line = text.substr(pos, end - pos);
    pos = end == std::string::npos ? text.size() : end + 1;
    if (line.find_first_not_of(" \r") == std::string::npos) continue;
    const std::size_t c1 = line.find(','), c2 = line.find(',', c1 + 1);
    out += line.substr(0, c1) + "," + fmt::format("{:.17g}", std::stod(line.substr(c1 + 1, c2 - c1 - 1)) * u_scale) +
           "," + fmt::format("{:.17g}", std::stod(line.substr(c2 + 1)) * y_scale) + "\n";
  }
  return WriteFile(name, out);
}

// dryer.csv with u and y multiplied by `scale`.
inline std::string ScaledDryer(const std::string& name, double scale) { return ScaledDryer(name, scale, scale); }

}  // namespace ident::testing
