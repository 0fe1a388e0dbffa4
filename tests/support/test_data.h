// Paths to the repository's datasets and the shared spec vectors, and small data helpers for tests.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

namespace ident::testing {

// <repo>/datasets/<name>
std::string DatasetPath(const std::string& name);
// <repo>/tests/data/shared/<relative>: the in-repository copy of the shared material tests need
// (spec/vectors/*), so that a clean clone tests without anything outside the repository.
std::string SharedPath(const std::string& relative);
// Reads a whole CSV with a header of column names into `names` and a row-major matrix (test helper;
// fails the test via exception on a bad file).
Eigen::MatrixXd ReadCsvMatrix(const std::string& path, std::vector<std::string>* names = nullptr);

}  // namespace ident::testing
