#include "tests/support/cli.h"

#include <gtest/gtest.h>

#include <algorithm>

#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "fuzz/fuzz_util.h"

namespace ident::testing {

std::string TempDir() {
  // Removed with its contents when the process exits normally (forked children leave with _exit).
  static const fuzz::ScratchDir dir("ident-test-");
  return dir.path();
}

std::string WriteFile(const std::string& name, const std::string& text) {
  const std::string path = TempDir() + "/" + name;
  std::ofstream(path, std::ios::binary) << text;
  return path;
}

std::string ReadFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

long ProcessBytesRead() {
  std::ifstream io("/proc/self/io");
  std::string key;
  long value = -1;
  while (io >> key >> value)
    if (key == "rchar:") return value;
  return -1;
}

CliResult RunCli(const std::string& args) {
#ifndef IDENT_CLI_PATH
  throw std::runtime_error("IDENT_CLI_PATH is not defined for this test executable");
#else
  static int counter = 0;
  const std::string base = TempDir() + "/run" + std::to_string(getpid()) + "_" + std::to_string(counter++);
  const std::string command =
      std::string("'") + IDENT_CLI_PATH + "' " + args + " > '" + base + ".out' 2> '" + base + ".err' < /dev/null";
  const int status = std::system(command.c_str());
  CliResult r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  r.out = ReadFile(base + ".out");
  r.err = ReadFile(base + ".err");
  return r;
#endif
}

void ExpectCliError(const std::string& args, const std::string& needle, int code) {
  const CliResult r = RunCli(args);
  EXPECT_EQ(r.exit_code, code) << args << "\nstderr: " << r.err;
  EXPECT_NE(r.err.find(needle), std::string::npos) << args << "\nstderr: " << r.err;
  if (code == 1) {
    EXPECT_EQ(r.err.rfind("ident: error: ", 0), 0u) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << "more than one line: " << r.err;
  }
  EXPECT_TRUE(r.out.empty()) << "stdout should be empty on error: " << r.out;
}

}  // namespace ident::testing
