// The `ident` command line as a function: parses argv, runs the subcommand and prints every error as one
// line "ident: error: <message>" on std::cerr. Returns the exit code (kExitOk, kExitBadInput,
// kExitUsage of cli/commands.h). main() (cli/main.cc) adds what only a process needs: the standard
// descriptors kept taken and the final check of standard output. The CLI fuzzer (fuzz/cli_fuzzer.cc)
// calls it in-process.
#pragma once

namespace ident::cli {

int RunCommandLine(int argc, char** argv);

// Prints "ident: error: cannot write to standard output: <strerror(error)>" and returns kExitBadInput.
int StandardOutputError(int error);

}  // namespace ident::cli
