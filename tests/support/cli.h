// Runs the `ident` program from a test and captures its exit code, stdout and stderr.
#pragma once

#include <string>

namespace ident::testing {

struct CliResult {
  int exit_code = -1;
  std::string out, err;
};

// `args` is appended to the program path as is (shell syntax). Requires IDENT_CLI_PATH.
CliResult RunCli(const std::string& args);

// A fresh temporary directory for this test process; WriteFile writes `text` to dir/name and returns the path.
std::string TempDir();
std::string WriteFile(const std::string& name, const std::string& text);
std::string ReadFile(const std::string& path);

// Bytes this process has read so far: rchar of /proc/self/io (every read of every thread, from any file); -1
// on a kernel without I/O accounting.
long ProcessBytesRead();

// Runs `args` and expects exit code `code`, `needle` in stderr, empty stdout and, for exit 1, exactly
// one stderr line starting "ident: error: " (gtest EXPECTs, so the calling test fails on a mismatch).
void ExpectCliError(const std::string& args, const std::string& needle, int code = 1);

}  // namespace ident::testing
