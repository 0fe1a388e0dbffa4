// The rows, line numbers and error of a CSV reader read to its end: what the reader tests compare.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "common/error.h"

namespace ident::io {

struct ReadRows {
  std::vector<double> values;
  std::vector<long> lines;
  std::string error;  // the DataError that ended the reading, if any
};

template <class Reader>
ReadRows ReadEvery(Reader& reader) {
  ReadRows out;
  Eigen::VectorXd row(reader.num_columns());
  try {
    while (reader.Next(row)) {
      out.values.insert(out.values.end(), row.data(), row.data() + row.size());
      out.lines.push_back(reader.line());
    }
  } catch (const DataError& e) {
    out.error = e.what();
  }
  return out;
}

}  // namespace ident::io
