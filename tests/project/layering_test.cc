// The library's layers include downwards only (docs/maintainer/architecture.md): every quoted #include of a file in common/,
// models/, approx/ and each folder of ident/ names a file of its own folder or of a folder below it.
//   common/             common/
//   models/, approx/    common/ and themselves
//   ident/linalg/       common/
//   ident/<concept>/    common/, models/, approx/, ident/linalg/ as listed below, and itself
// No folder of ident/ includes another except linalg/, observers/, which runs its log-concave Gaussian filter as a
// regression estimator started by a batch fit of regression/, registry/, which builds the estimators of
// regression/ and observers/ by name, and workflow/, which builds on registry/, regression/, smoothing/ and io/.
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <string>
#include <vector>

#include <gtest/gtest.h>

namespace ident {
namespace {

namespace fs = std::filesystem;

// The folder a repository path belongs to: "common", "models", "approx" or "ident/<concept>".
std::string Layer(const std::string& path) {
  const auto slash = path.find('/');
  const std::string top = path.substr(0, slash);
  if (top != "ident" || slash == std::string::npos) return top;
  const auto next = path.find('/', slash + 1);
  return next == std::string::npos ? path : path.substr(0, next);
}

const std::map<std::string, std::set<std::string>>& Allowed() {
  static const std::map<std::string, std::set<std::string>> allowed = {
      {"common", {"common"}},
      {"models", {"common", "models"}},
      {"approx", {"common", "approx"}},
      {"ident/linalg", {"common", "ident/linalg"}},
      {"ident/regression", {"common", "approx", "ident/linalg", "ident/regression"}},
      {"ident/observers", {"common", "models", "approx", "ident/linalg", "ident/regression", "ident/observers"}},
      {"ident/registry",
       {"common", "models", "approx", "ident/linalg", "ident/observers", "ident/regression", "ident/registry"}},
      {"ident/smoothing", {"common", "models", "ident/linalg", "ident/smoothing"}},
      {"ident/density", {"common", "models", "ident/density"}},
      {"ident/control", {"common", "ident/control"}},
      {"ident/io", {"common", "ident/io"}},
      {"ident/workflow",
       {"common", "models", "approx", "ident/linalg", "ident/regression", "ident/registry", "ident/smoothing",
        "ident/io", "ident/workflow"}},
  };
  return allowed;
}

TEST(Layering, LibraryIncludesRunDownwardsOnly) {
  const fs::path root = IDENT_SOURCE_DIR;
  const std::regex include(R"re(^\s*#\s*include\s+"([^"]+)")re");
  int files = 0;
  std::vector<std::string> violations;
  for (const char* top : {"common", "models", "approx", "ident"}) {
    for (const auto& entry : fs::recursive_directory_iterator(root / top)) {
      const std::string ext = entry.path().extension().string();
      if (!entry.is_regular_file() || (ext != ".h" && ext != ".cc")) continue;
      const std::string path = fs::relative(entry.path(), root).generic_string();
      const std::string layer = Layer(path);
      const auto allowed = Allowed().find(layer);
      if (allowed == Allowed().end()) {
        violations.push_back(
            path + ": a folder the layering does not know (add it to docs/maintainer/architecture.md and here)");
        continue;
      }
      ++files;
      std::ifstream in(entry.path());
      std::string line;
      std::smatch m;
      while (std::getline(in, line))
        if (std::regex_search(line, m, include) && !allowed->second.count(Layer(m[1].str())))
          violations.push_back(path + " includes " + m[1].str());
    }
  }
  EXPECT_GT(files, 80);
  for (const std::string& v : violations) ADD_FAILURE() << v;
}

// The checker sees a violation when there is one.
TEST(Layering, LayerOfAPathIsItsFolder) {
  EXPECT_EQ(Layer("common/error.h"), "common");
  EXPECT_EQ(Layer("ident/regression/internal/step_guard.h"), "ident/regression");
  EXPECT_EQ(Layer("models/arx.h"), "models");
  EXPECT_FALSE(Allowed().at("models").count(Layer("ident/regression/rls.h")));
  EXPECT_FALSE(Allowed().at("approx").count(Layer("models/penalties.h")));
}

}  // namespace
}  // namespace ident
