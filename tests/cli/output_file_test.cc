// OutputFile (cli/output_file.h) and CheckOutputPaths (cli/output_paths.h): complete content or the
// old content, never a partial file, no temporary file left behind, including on SIGTERM and SIGINT.
#include <gtest/gtest.h>

#include <signal.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "cli/output_file.h"
#include "cli/output_paths.h"
#include "common/error.h"
#include "tests/support/cli.h"

namespace ident::testing {
namespace {

namespace fs = std::filesystem;
using cli::CheckOutputPaths;
using cli::OutputFile;

// A fresh empty directory for one test.
fs::path FreshDir(const std::string& name) {
  const fs::path dir = fs::path(TempDir()) / ("output_file_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

// The names in `dir`, sorted, joined by spaces.
std::string Listing(const fs::path& dir) {
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  std::string out;
  for (const auto& n : names) out += (out.empty() ? "" : " ") + n;
  return out;
}

std::string ErrorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const InvalidArgument& e) {
    return e.what();
  }
  return "";
}

TEST(OutputFile, CommitReplacesTheTargetAndKeepsItsMode) {
  const fs::path dir = FreshDir("commit");
  const std::string target = (dir / "t.csv").string();
  WriteFile("output_file_commit/t.csv", "old content\n");
  ASSERT_EQ(chmod(target.c_str(), 0640), 0);
  {
    OutputFile out(target, "--trace file");
    EXPECT_EQ(Listing(dir).find(".t.csv.tmp-") != std::string::npos, true) << Listing(dir);
    out.Write("t,y\n");
    fmt::print(out.stream(), "{},{}\n", 1, 2.5);
    EXPECT_EQ(ReadFile(target), "old content\n");  // untouched until the commit
    out.Commit();
    EXPECT_TRUE(out.committed());
  }
  EXPECT_EQ(ReadFile(target), "t,y\n1,2.5\n");
  EXPECT_EQ(Listing(dir), "t.csv");
  struct stat st {};
  ASSERT_EQ(stat(target.c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 07777, 0640u);
  EXPECT_EQ(cli::PendingOutputFiles(), 0);
}

TEST(OutputFile, WithoutCommitTheTargetKeepsItsBytesAndNoTemporaryFileRemains) {
  const fs::path dir = FreshDir("abandon");
  const std::string old(10000, 'x');
  const std::string target = WriteFile("output_file_abandon/keep", old);
  {
    OutputFile out(target, "--trace file");
    out.Write(std::string(20000, 'y'));
    out.Close();  // closed but not renamed
    EXPECT_EQ(cli::PendingOutputFiles(), 1);
  }
  EXPECT_EQ(ReadFile(target), old);
  EXPECT_EQ(Listing(dir), "keep");
  EXPECT_EQ(cli::PendingOutputFiles(), 0);
  // A new name that fails is not created at all.
  {
    OutputFile out((dir / "new.csv").string(), "--csv file");
    out.Write("partial");
  }
  EXPECT_EQ(Listing(dir), "keep");
}

TEST(OutputFile, SymbolicLinkIsWrittenThroughAndStaysALink) {
  const fs::path dir = FreshDir("link");
  const std::string real = WriteFile("output_file_link/real.csv", "old\n");
  fs::create_symlink("real.csv", dir / "link.csv");
  {
    OutputFile out((dir / "link.csv").string(), "--trace file");
    out.Write("aborted\n");
  }
  EXPECT_EQ(ReadFile(real), "old\n");
  EXPECT_TRUE(fs::is_symlink(dir / "link.csv"));
  {
    OutputFile out((dir / "link.csv").string(), "--trace file");
    out.Write("new\n");
    out.Commit();
  }
  EXPECT_TRUE(fs::is_symlink(dir / "link.csv"));
  EXPECT_EQ(fs::read_symlink(dir / "link.csv"), "real.csv");
  EXPECT_EQ(ReadFile(real), "new\n");
  EXPECT_EQ(Listing(dir), "link.csv real.csv");
  // A dangling link creates the file it names.
  fs::create_symlink("later.csv", dir / "dangling.csv");
  {
    OutputFile out((dir / "dangling.csv").string(), "--trace file");
    out.Write("made\n");
    out.Commit();
  }
  EXPECT_TRUE(fs::is_symlink(dir / "dangling.csv"));
  EXPECT_EQ(ReadFile((dir / "later.csv").string()), "made\n");
}

TEST(OutputFile, RefusesDevicesDirectoriesAndMissingDirectoriesNamingTheFile) {
  const fs::path dir = FreshDir("refuse");
  // A private /dev/full node (root only), so that a regression cannot remove the system's.
  const fs::path full = dir / "full";
  if (mknod(full.c_str(), S_IFCHR | 0666, makedev(1, 7)) == 0) {
    EXPECT_EQ(
        ErrorOf([&] { OutputFile(full.string(), "--csv file"); }),
        fmt::format("cannot write --csv file '{}': not a regular file (a device, fifo or directory)", full.string()));
    EXPECT_TRUE(fs::is_character_file(full));
    fs::remove(full);
  }
  EXPECT_EQ(
      ErrorOf([&] { OutputFile(dir.string(), "--trace file"); }),
      fmt::format("cannot write --trace file '{}': not a regular file (a device, fifo or directory)", dir.string()));
  EXPECT_EQ(
      ErrorOf([&] { OutputFile((dir / "no/such/dir.csv").string(), "--trace file"); }),
      fmt::format("cannot write --trace file '{}': No such file or directory", (dir / "no/such/dir.csv").string()));
  ASSERT_EQ(mkfifo((dir / "fifo").c_str(), 0600), 0);
  EXPECT_NE(ErrorOf([&] { OutputFile((dir / "fifo").string(), "--trace file"); }).find("not a regular file"),
            std::string::npos);
  EXPECT_EQ(Listing(dir), "fifo");
  EXPECT_EQ(cli::PendingOutputFiles(), 0);
}

// A child process writes part of a file and receives `signal_number`: it dies by that signal, its
// temporary file is gone and the target has its old bytes.
void ExpectSignalRemovesTheTemporaryFile(int signal_number, const std::string& name) {
  const fs::path dir = FreshDir(name);
  const std::string old = "line 1\nline 2\n";
  const std::string target = WriteFile("output_file_" + name + "/target.csv", old);
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    OutputFile out(target, "--trace file");
    out.Write(std::string(100000, 'p'));
    std::fflush(out.stream());
    raise(signal_number);
    _exit(3);  // not reached: the handler re-raises with the default action
  }
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFSIGNALED(status)) << "exit status " << status;
  EXPECT_EQ(WTERMSIG(status), signal_number);
  EXPECT_EQ(ReadFile(target), old);
  EXPECT_EQ(Listing(dir), "target.csv");
}

TEST(OutputFile, SigtermRemovesTheTemporaryFileAndLeavesTheTarget) {
  ExpectSignalRemovesTheTemporaryFile(SIGTERM, "sigterm");
}

TEST(OutputFile, SigintRemovesTheTemporaryFileAndLeavesTheTarget) {
  ExpectSignalRemovesTheTemporaryFile(SIGINT, "sigint");
}

TEST(CheckOutputPaths, RefusesAnInputTwoEqualOutputsStdoutAndDevices) {
  const fs::path dir = FreshDir("paths");
  const std::string data = WriteFile("output_file_paths/d.csv", "u,y\n1,2\n");
  fs::create_symlink("d.csv", dir / "alias.csv");
  fs::create_hard_link(data, dir / "hard.csv");
  const std::string alias = (dir / "alias.csv").string(), hard = (dir / "hard.csv").string();
  EXPECT_EQ(ErrorOf([&] {
              CheckOutputPaths({{"--trace", data}}, {{"input data file", data}});
            }),
            fmt::format("--trace file '{0}' is the input data file '{0}'; give another name", data));
  EXPECT_NE(ErrorOf([&] { CheckOutputPaths({{"--trace", alias}}, {{"input data file", data}}); }), "");
  EXPECT_NE(ErrorOf([&] { CheckOutputPaths({{"--trace", hard}}, {{"input data file", data}}); }), "");
  const std::string x = (dir / "x.csv").string(), x2 = (dir / "sub/../x.csv").string();
  fs::create_directories(dir / "sub");
  EXPECT_EQ(ErrorOf([&] {
              CheckOutputPaths({{"--csv", x}, {"--trace", x2}}, {});
            }),
            fmt::format("--csv and --trace name the same file ('{}', '{}'); give two names", x, x2));
  EXPECT_NE(ErrorOf([] {
              CheckOutputPaths({{"--trace", "-"}}, {});
            }).find("writing to standard output"),
            std::string::npos);
  EXPECT_NE(ErrorOf([&] {
              CheckOutputPaths({{"--csv", dir.string()}}, {});
            }).find("not a regular file"),
            std::string::npos);
  EXPECT_EQ(ErrorOf([&] {
              CheckOutputPaths({{"--csv", x}, {"--trace", ""}, {"--plot", (dir / "p.svg").string()}},
                               {{"input data file", data}, {"--prior file", ""}});
            }),
            "");
  EXPECT_EQ(Listing(dir), "alias.csv d.csv hard.csv sub");  // checking creates nothing
}

}  // namespace
}  // namespace ident::testing
