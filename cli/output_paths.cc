#include "cli/output_paths.h"

#include <filesystem>
#include <system_error>

#include <fmt/format.h>

#include "common/error.h"

namespace ident::cli {
namespace {

namespace fs = std::filesystem;

// True when `a` and `b` are the same file: the same inode if both exist, else the same path once the
// existing part of each is resolved.
bool SameFile(const std::string& a, const std::string& b) {
  std::error_code ec;
  if (fs::exists(a, ec) && fs::exists(b, ec)) return fs::equivalent(a, b, ec) && !ec;
  const fs::path ca = fs::weakly_canonical(fs::absolute(a, ec), ec);
  if (ec) return false;
  const fs::path cb = fs::weakly_canonical(fs::absolute(b, ec), ec);
  return !ec && ca == cb;
}

}  // namespace

void CheckOutputPaths(const std::vector<NamedPath>& outputs, const std::vector<NamedPath>& inputs) {
  for (std::size_t i = 0; i < outputs.size(); ++i) {
    const NamedPath& out = outputs[i];
    if (out.path.empty()) continue;
    IDENT_REQUIRE(out.path != "-",
                  "{} '-': writing to standard output is not supported; give a file name (./- for a "
                  "file named '-')",
                  out.name);
    std::error_code ec;
    const fs::file_status status = fs::status(out.path, ec);  // follows symbolic links
    IDENT_REQUIRE(!fs::exists(status) || fs::is_regular_file(status),
                  "cannot write {} file '{}': not a regular file (a device, fifo or directory)", out.name, out.path);
    for (const NamedPath& in : inputs) {
      if (in.path.empty()) continue;
      IDENT_REQUIRE(!SameFile(out.path, in.path), "{} file '{}' is the {} '{}'; give another name", out.name, out.path,
                    in.name, in.path);
    }
    for (std::size_t j = 0; j < i; ++j) {
      const NamedPath& other = outputs[j];
      if (other.path.empty()) continue;
      IDENT_REQUIRE(!SameFile(out.path, other.path), "{} and {} name the same file ('{}', '{}'); give two names",
                    other.name, out.name, other.path, out.path);
    }
  }
}

}  // namespace ident::cli
