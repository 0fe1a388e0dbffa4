// ident — recursive, outlier-robust system identification from the command line.
#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <exception>
#include <iostream>
#include <string>
#include <system_error>

#include <CLI/CLI.hpp>

#include "ident/common/error.h"
#include "tools/commands.h"

namespace {

using namespace ident::tools;

// Keeps descriptors 0-2 taken. A program started with one of them closed would otherwise get it for the
// first file it opens (an input, an output's temporary file), and the report would land in that file. A
// closed descriptor becomes /dev/null opened for the other direction, so that writing to a closed
// stdout fails (EBADF) and is reported like any other write error.
void OccupyStandardDescriptors() {
  for (int fd = 0; fd <= 2; ++fd) {
    if (fcntl(fd, F_GETFD) != -1 || errno != EBADF) continue;
    const int got = open("/dev/null", fd == 0 ? O_WRONLY : O_RDONLY);
    if (got >= 0 && got != fd) {
      dup2(got, fd);
      close(got);
    }
  }
}

int StandardOutputError(int error) {
  std::cerr << "ident: error: cannot write to standard output: " << std::strerror(error ? error : EIO) << "\n";
  return kExitBadInput;
}

// Flushes stdout (C stdio, which fmt::print uses and std::cout is synchronised with) and reports a write
// that failed at any point: a full disk, a closed or read-only descriptor.
int FinishStandardOutput() {
  errno = 0;
  std::cout.flush();  // flushes stdout itself (the synchronised stream buffer calls fflush)
  const int cout_error = errno;
  errno = 0;
  const bool flushed = std::fflush(stdout) == 0;
  const int error = errno ? errno : cout_error;
  if (flushed && !std::ferror(stdout) && std::cout.good()) return kExitOk;
  return StandardOutputError(error);
}

int Run(int argc, char** argv) {
  CLI::App app{"ident: recursive, outlier-robust system identification", "ident"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "ident 0.1.0");
  AddFitCommand(app);
  AddDatasetsCommand(app);
  AddCompareCommand(app);
  AddMemsCommand(app);
  AddLogcondensCommand(app);
  AddSmoothCommand(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    // One line, like every other error. A first argument that is no option and no subcommand is named.
    std::string message = e.what();
    if (argc >= 2 && argv[1][0] != '-') {
      const std::string first = argv[1];
      bool known = false;
      for (const CLI::App* sub : app.get_subcommands({})) known = known || sub->check_name(first);
      if (!known) {
        message = "unknown subcommand '" + first + "' (known:";
        for (const CLI::App* sub : app.get_subcommands({})) message += " " + sub->get_name();
        message += ")";
      }
    }
    std::cerr << "ident: error: " << message << " (ident --help, ident SUBCOMMAND --help for usage)\n";
    return kExitUsage;
  } catch (const ident::InvalidArgument& e) {
    std::cerr << "ident: error: " << e.what() << "\n";
    return kExitBadInput;
  } catch (const ident::DataError& e) {
    std::cerr << "ident: error: " << e.what() << "\n";
    return kExitBadInput;
  } catch (const std::system_error& e) {  // fmt::print to stdout failing
    if (std::ferror(stdout)) return StandardOutputError(e.code().value());
    std::cerr << "ident: error: " << e.what() << "\n";
    return kExitBadInput;
  } catch (const std::exception& e) {
    std::cerr << "ident: error: " << e.what() << "\n";
    return kExitBadInput;
  }
  return kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  OccupyStandardDescriptors();
  const int code = Run(argc, argv);
  return code == kExitOk ? FinishStandardOutput() : code;
}
