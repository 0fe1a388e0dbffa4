#include "tests/support/test_data.h"

#include <fstream>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace ident::testing {

std::string DatasetPath(const std::string& name) { return std::string(IDENT_SOURCE_DIR) + "/datasets/" + name; }
std::string SharedPath(const std::string& relative) { return std::string(IDENT_SHARED_DIR) + "/" + relative; }

Eigen::MatrixXd ReadCsvMatrix(const std::string& path, std::vector<std::string>* names) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot open " + path);
  std::string line;
  std::getline(in, line);
  if (names) {
    names->clear();
    std::stringstream ss(line);
    for (std::string cell; std::getline(ss, cell, ',');) names->push_back(cell);
  }
  std::vector<std::vector<double>> rows;
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    std::vector<double> row;
    std::stringstream ss(line);
    for (std::string cell; std::getline(ss, cell, ',');) row.push_back(std::stod(cell));
    rows.push_back(std::move(row));
  }
  Eigen::MatrixXd m(rows.size(), rows.empty() ? 0 : rows[0].size());
  for (std::size_t i = 0; i < rows.size(); ++i)
    for (std::size_t j = 0; j < rows[i].size(); ++j) m(i, j) = rows[i][j];
  return m;
}

}  // namespace ident::testing
