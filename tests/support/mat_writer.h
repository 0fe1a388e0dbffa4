// Writes MATLAB .mat files with libmatio for the .mat reader's tests (ident/io/mat_file.h). Only where
// the tests are built with libmatio (IDENT_HAVE_MATIO, tests/CMakeLists.txt).
#pragma once

#if IDENT_HAVE_MATIO
#include <matio.h>

#include <complex>
#include <stdexcept>
#include <string>
#include <vector>

namespace ident::testing {

// One variable: its name, its dimensions and its values in column-major order.
struct MatVariable {
  std::string name;
  std::vector<std::size_t> dims;
  std::vector<double> values;
  enum Kind { kDouble, kInt32, kChar, kComplex } kind = kDouble;
};

inline void WriteMatFile(const std::string& path, mat_ft version, const std::vector<MatVariable>& variables) {
  mat_t* mat = Mat_CreateVer(path.c_str(), nullptr, version);
  if (mat == nullptr) throw std::runtime_error("cannot create " + path);
  for (const MatVariable& v : variables) {
    std::vector<std::size_t> dims = v.dims;
    // Converted only for their own kind: a double variable may hold values beyond int's range.
    std::vector<std::int32_t> ints;
    std::vector<char> chars;
    if (v.kind == MatVariable::kInt32) ints.assign(v.values.begin(), v.values.end());
    if (v.kind == MatVariable::kChar) chars.assign(v.values.begin(), v.values.end());
    std::vector<double> re = v.values, im(v.values.size(), 0.5);
    mat_complex_split_t split{re.data(), im.data()};
    matvar_t* var = nullptr;
    const int rank = static_cast<int>(dims.size());
    switch (v.kind) {
      case MatVariable::kDouble:
        var = Mat_VarCreate(v.name.c_str(), MAT_C_DOUBLE, MAT_T_DOUBLE, rank, dims.data(),
                            const_cast<double*>(v.values.data()), 0);
        break;
      case MatVariable::kInt32:
        var = Mat_VarCreate(v.name.c_str(), MAT_C_INT32, MAT_T_INT32, rank, dims.data(), ints.data(), 0);
        break;
      case MatVariable::kChar:
        var = Mat_VarCreate(v.name.c_str(), MAT_C_CHAR, MAT_T_UINT8, rank, dims.data(), chars.data(), 0);
        break;
      case MatVariable::kComplex:
        var = Mat_VarCreate(v.name.c_str(), MAT_C_DOUBLE, MAT_T_DOUBLE, rank, dims.data(), &split, MAT_F_COMPLEX);
        break;
    }
    if (var == nullptr || Mat_VarWrite(mat, var, MAT_COMPRESSION_NONE) != 0) {
      Mat_VarFree(var);
      Mat_Close(mat);
      throw std::runtime_error("cannot write variable " + v.name + " to " + path);
    }
    Mat_VarFree(var);
  }
  Mat_Close(mat);
}

}  // namespace ident::testing
#endif
