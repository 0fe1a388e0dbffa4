#include "ident/io/mat_file.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <memory>
#include <unordered_set>
#include <vector>

#include <fmt/format.h>

#include "common/error.h"

#if IDENT_HAVE_MATIO
#include <matio.h>
#endif

namespace ident::io {

bool IsMatFile(const std::string& path) {
  if (path.size() < 4) return false;
  std::string ext = path.substr(path.size() - 4);
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext == ".mat";
}

DataTable ReadDataFile(const std::string& path, const CsvOptions& options) {
  return IsMatFile(path) ? ReadMat(path, options) : ReadCsv(path, options);
}

#if IDENT_HAVE_MATIO

bool MatFilesSupported() { return true; }

namespace {

// libmatio logs to stderr by default; the reader's messages say what went wrong instead.
void QuietMatioLog(int, char*) {}

struct MatCloser {
  void operator()(mat_t* m) const { Mat_Close(m); }
};
struct MatVarFreer {
  void operator()(matvar_t* v) const { Mat_VarFree(v); }
};
using MatFile = std::unique_ptr<mat_t, MatCloser>;
using MatVar = std::unique_ptr<matvar_t, MatVarFreer>;

bool IsNumeric(matio_classes c) { return c >= MAT_C_DOUBLE && c <= MAT_C_UINT64; }

template <class T>
void CopyAs(const void* data, std::size_t n, std::vector<double>& out) {
  const T* p = static_cast<const T*>(data);
  out.assign(n, 0.0);
  for (std::size_t i = 0; i < n; ++i) out[i] = static_cast<double>(p[i]);
}

// The variable's values in column-major order, as doubles.
std::vector<double> Values(const matvar_t& v, std::size_t n) {
  std::vector<double> out;
  switch (v.class_type) {
    case MAT_C_DOUBLE:
      CopyAs<double>(v.data, n, out);
      break;
    case MAT_C_SINGLE:
      CopyAs<float>(v.data, n, out);
      break;
    case MAT_C_INT8:
      CopyAs<std::int8_t>(v.data, n, out);
      break;
    case MAT_C_UINT8:
      CopyAs<std::uint8_t>(v.data, n, out);
      break;
    case MAT_C_INT16:
      CopyAs<std::int16_t>(v.data, n, out);
      break;
    case MAT_C_UINT16:
      CopyAs<std::uint16_t>(v.data, n, out);
      break;
    case MAT_C_INT32:
      CopyAs<std::int32_t>(v.data, n, out);
      break;
    case MAT_C_UINT32:
      CopyAs<std::uint32_t>(v.data, n, out);
      break;
    case MAT_C_INT64:
      CopyAs<std::int64_t>(v.data, n, out);
      break;
    case MAT_C_UINT64:
      CopyAs<std::uint64_t>(v.data, n, out);
      break;
    default:
      break;
  }
  return out;
}

struct MatColumns {
  std::string variable;
  std::size_t rows = 0, cols = 0;  // the record's rows = rows; one column per cols
  std::vector<double> values;      // column-major
};

}  // namespace

DataTable ReadMat(const std::string& path, const CsvOptions& options) {
  static const int log_set = Mat_LogInitFunc("ident", QuietMatioLog);
  (void)log_set;
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    throw DataError(fmt::format("cannot read '{}': it is a directory", path));
  if (!std::filesystem::exists(path, ec))
    throw DataError(fmt::format("cannot open '{}': No such file or directory", path));
  MatFile file(Mat_Open(path.c_str(), MAT_ACC_RDONLY));
  if (!file) throw DataError(fmt::format("cannot open '{}' as a MATLAB file (v5, v7 or v7.3)", path));
  std::vector<MatColumns> found;
  std::vector<std::string> scalars;  // names of 1x1 variables, kept if the record has one row
  std::vector<MatColumns> scalar_values;
  while (true) {
    MatVar info(Mat_VarReadNextInfo(file.get()));
    if (!info) break;
    const std::string name = info->name ? info->name : "";
    if (!IsNumeric(info->class_type) || name.empty()) continue;  // text, cells, structs, sparse, empty
    if (info->rank != 2)
      throw DataError(fmt::format("{}: variable {} has {} dimensions; columns are vectors or matrices", path,
                                  ShowCell(name), info->rank));
    if (info->isComplex) throw DataError(fmt::format("{}: variable {} is complex", path, ShowCell(name)));
    std::size_t r = info->dims[0], c = info->dims[1];
    if (r == 0 || c == 0) continue;
    MatVar var(Mat_VarRead(file.get(), name.c_str()));
    if (!var || !var->data) throw DataError(fmt::format("{}: cannot read variable {}", path, ShowCell(name)));
    MatColumns m{name, r, c, Values(*var, r * c)};
    if (r == 1) std::swap(m.rows, m.cols);  // a 1xN row is a vector of N samples
    (m.rows == 1 && m.cols == 1 ? scalar_values : found).push_back(std::move(m));
  }
  if (found.empty()) found = std::move(scalar_values);  // a record of one row
  if (found.empty()) throw DataError(fmt::format("{}: no numeric variable", path));
  const auto longest = std::max_element(found.begin(), found.end(),
                                        [](const MatColumns& a, const MatColumns& b) { return a.rows < b.rows; });
  const std::size_t rows = longest->rows;
  std::size_t columns = 0;
  for (const MatColumns& m : found) {
    if (m.rows != rows)
      throw DataError(fmt::format("{}: variable {} has {} samples; {} has {}", path, ShowCell(m.variable), m.rows,
                                  ShowCell(longest->variable), rows));
    columns += m.cols;
  }
  if (columns > static_cast<std::size_t>(kMaxCsvColumns))
    throw DataError(fmt::format("{}: {} columns; at most {} are supported", path, columns, kMaxCsvColumns));
  DataTable table;
  table.source = path;
  table.values.resize(static_cast<Eigen::Index>(rows), static_cast<Eigen::Index>(columns));
  std::unordered_set<std::string> names;
  Eigen::Index j = 0;
  for (const MatColumns& m : found) {
    for (std::size_t k = 0; k < m.cols; ++k, ++j) {
      std::string name = m.cols == 1 ? m.variable : fmt::format("{}_{}", m.variable, k + 1);
      if (!names.insert(name).second)
        throw DataError(
            fmt::format("{}: two columns named {} (variable {})", path, ShowCell(name), ShowCell(m.variable)));
      for (std::size_t i = 0; i < rows; ++i) {
        double v = m.values[k * rows + i];
        if (!std::isfinite(v)) {
          if (!options.missing_as_nan)
            throw DataError(fmt::format(
                "{}: variable {}, row {}: {} is not a finite number (pass --missing to treat NaN/Inf values as "
                "missing samples)",
                path, ShowCell(name), i + 1, v));
          v = std::numeric_limits<double>::quiet_NaN();
        }
        table.values(static_cast<Eigen::Index>(i), j) = v;
      }
      table.names.push_back(std::move(name));
    }
  }
  return table;
}

#else

bool MatFilesSupported() { return false; }

DataTable ReadMat(const std::string& path, const CsvOptions&) {
  throw DataError(fmt::format("{}: this build reads no .mat files (libmatio was not found when it was built)", path));
}

#endif

}  // namespace ident::io
