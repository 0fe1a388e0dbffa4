// The README shows what the program prints, and its C++ example compiles and runs (readme.cpp_example,
// tests/CMakeLists.txt). Every "$ ident …" line in a ``` block of README.md is run; each line of the
// output shown under it must be a line of what the command prints — with "<repository>" standing for the
// checkout's root and the last column of a `compare` table (ns/update, a timing) left out on both sides.
#include <algorithm>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "tests/support/cli.h"

namespace ident::testing {
namespace {

std::vector<std::string> Lines(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

// A line as compared: "<repository>" replaced, a compare-table row without its timing column.
std::string Normalised(std::string line) {
  const std::string marker = "<repository>";
  if (const auto at = line.find(marker); at != std::string::npos) line.replace(at, marker.size(), IDENT_SOURCE_DIR);
  if (line.find(" recursive ") != std::string::npos || line.find(" batch ") != std::string::npos ||
      line.find("ns/update") != std::string::npos) {
    const auto end = line.find_last_not_of(' ');
    const auto last = line.find_last_of(' ', end);
    if (last != std::string::npos) line.erase(last);
  }
  line.erase(line.find_last_not_of(' ') + 1);  // the timing's width varies
  return line;
}

TEST(Readme, CommandLineExamplesPrintWhatTheReadmeShows) {
  const std::vector<std::string> readme = Lines(ReadFile(std::string(IDENT_SOURCE_DIR) + "/README.md"));
  int examples = 0;
  bool in_block = false;
  for (std::size_t i = 0; i < readme.size(); ++i) {
    if (readme[i].rfind("```", 0) == 0) {
      in_block = !in_block;
      continue;
    }
    if (!in_block || readme[i].rfind("$ ident ", 0) != 0) continue;
    const std::string args = readme[i].substr(std::string("$ ident ").size());
    const CliResult r = RunCli(args);
    ASSERT_EQ(r.exit_code, 0) << args << ": " << r.err;
    std::vector<std::string> printed;
    for (const std::string& line : Lines(r.out)) printed.push_back(Normalised(line));
    int shown = 0;
    for (std::size_t j = i + 1; j < readme.size() && readme[j].rfind("```", 0) != 0; ++j, ++shown) {
      const std::string expected = Normalised(readme[j]);
      EXPECT_NE(std::find(printed.begin(), printed.end(), expected), printed.end())
          << "README line " << j + 1 << " (ident " << args << ") is not printed:\n"
          << expected << "\nprinted:\n"
          << r.out;
    }
    EXPECT_GT(shown, 3) << args;
    ++examples;
  }
  EXPECT_GE(examples, 2);
}

}  // namespace
}  // namespace ident::testing
