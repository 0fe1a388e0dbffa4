// ident — recursive, outlier-robust system identification from the command line.
#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <iostream>

#include "cli/command_line.h"
#include "cli/commands.h"

namespace {

using namespace ident::cli;

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

}  // namespace

int main(int argc, char** argv) {
  OccupyStandardDescriptors();
  const int code = RunCommandLine(argc, argv);
  return code == kExitOk ? FinishStandardOutput() : code;
}
