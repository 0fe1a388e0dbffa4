// Test helper: the shared spec vectors (shared/spec/vectors/<case>.csv and <case>_init.csv) [spec §11].
#pragma once

#include <cmath>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "ident/regression/regression_prior.h"
#include "ident/regression/student_regression.h"
#include "tests/support/test_data.h"

namespace ident::testing {

struct SpecVector {
  std::string name;
  std::vector<std::string> columns;  // t, y, z1..zρ, nu, beta, xi, xi_z, pred_err, beta0, beta_hi, theta1..ρ, Dy
  Eigen::MatrixXd rows;
  std::map<std::string, double> init;  // numeric keys of <case>_init.csv
  int rho = 0;

  int col(const std::string& c) const {
    for (std::size_t i = 0; i < columns.size(); ++i)
      if (columns[i] == c) return static_cast<int>(i);
    throw std::runtime_error(name + ": no column " + c);
  }
  RegressionPrior Prior(const std::string& prefix = "V0", const std::string& nu_key = "nu0") const {
    RegressionPrior p;
    p.nu0 = init.at(nu_key);
    p.V0.resize(rho + 1, rho + 1);
    for (int i = 0; i <= rho; ++i)
      for (int j = 0; j <= rho; ++j) p.V0(i, j) = init.at(prefix + "_" + std::to_string(i) + "_" + std::to_string(j));
    return p;
  }
  bool stabilised() const { return init.count("nu_alt") > 0; }
  StudentRegressionOptions Options() const {
    StudentRegressionOptions o;
    o.dof = init.at("k");
    o.delta = static_cast<int>(init.at("delta"));
    o.forgetting.factor = init.at("lambda");
    o.forgetting.stabilised = stabilised();
    o.prior = Prior();
    return o;
  }
};

inline SpecVector ReadSpecVector(const std::string& name) {
  SpecVector v;
  v.name = name;
  v.rows = ReadCsvMatrix(SharedPath("spec/vectors/" + name + ".csv"), &v.columns);
  std::ifstream in(SharedPath("spec/vectors/" + name + "_init.csv"));
  if (!in) throw std::runtime_error("cannot open init of " + name);
  std::string line;
  std::getline(in, line);  // key,value
  while (std::getline(in, line)) {
    const auto comma = line.find(',');
    if (comma == std::string::npos) continue;
    const std::string key = line.substr(0, comma), value = line.substr(comma + 1);
    try {
      std::size_t used = 0;
      const double x = std::stod(value, &used);
      if (used == value.size()) v.init[key] = x;
    } catch (const std::exception&) {  // the note and the method are text
    }
  }
  v.rho = static_cast<int>(v.init.at("rho"));
  return v;
}

// |a − b| ≤ 1e−9·|b|, or ≤ 1e−12 when |b| < 1e−3 [spec §10.12].
inline bool VectorClose(double a, double b, double rel = 1e-9, double abs_small = 1e-12) {
  if (std::abs(b) < 1e-3) return std::abs(a - b) <= abs_small;
  return std::abs(a - b) <= rel * std::abs(b);
}

inline const std::vector<std::string>& SharedVectorNames() {
  static const std::vector<std::string> names = {"case_ii_rho4_arx", "case_ii_rho4_arx_expforget",
                                                 "case_ii_rho4_arx_stabforget"};
  return names;
}

}  // namespace ident::testing
