// The output files of every command end to end: a failed run leaves every existing file byte for byte
// as it was, an output that names an input (or another output, or a device) is refused before any work,
// and a failed write to a file or to standard output exits 1 with one line.
#include <gtest/gtest.h>

#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <cstdio>

#include <cstdlib>
#include <filesystem>
#include <sstream>
#include <string>

#include "ident/io/csv.h"
#include "tests/support/cli.h"
#include "tests/support/test_data.h"

namespace ident::testing {
namespace {

namespace fs = std::filesystem;

const std::string kDryerArx = " --output y --input u --na 2 --nb 2 --nk 3";
// The grid unrefined (--grid-tolerance 0) and EP on single readings (--ep-window 1): these tests are about
// the output files, not the observers.
const std::string kSmallMems = "mems --steps 400 --grid-points 16 --grid-tolerance 0 --t-mean 1 --ep-window 1";

// A fresh directory for one test, holding a copy of datasets/dryer.csv as d.csv.
fs::path DirWithDryer(const std::string& name) {
  const fs::path dir = fs::path(TempDir()) / ("outputs_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  fs::copy_file(DatasetPath("dryer.csv"), dir / "d.csv");
  fs::permissions(dir / "d.csv", fs::perms::owner_write, fs::perm_options::add);
  return dir;
}

std::string Q(const fs::path& p) { return "'" + p.string() + "'"; }

// Names in `dir` that look like temporary files of OutputFile.
int TemporaryFiles(const fs::path& dir) {
  int n = 0;
  for (const auto& e : fs::directory_iterator(dir))
    n += e.path().filename().string().find(".tmp-") != std::string::npos;
  return n;
}

TEST(OutputFilesCli, TraceNamingTheDataFileIsRefusedAndTheDataKept) {
  const fs::path dir = DirWithDryer("trace_is_data");
  const std::string before = ReadFile((dir / "d.csv").string());
  ASSERT_EQ(before.size(), 20881u);
  ExpectCliError("fit " + Q(dir / "d.csv") + kDryerArx + " --trace " + Q(dir / "d.csv"),
                 "--trace file '" + (dir / "d.csv").string() + "' is the input data file");
  EXPECT_EQ(ReadFile((dir / "d.csv").string()), before);
  // Through a symbolic link, a hard link and a different spelling of the same path.
  fs::create_symlink("d.csv", dir / "alias.csv");
  fs::create_hard_link(dir / "d.csv", dir / "hard.csv");
  for (const std::string trace : {"alias.csv", "hard.csv", "./../outputs_trace_is_data/d.csv"})
    ExpectCliError("fit " + Q(dir / "d.csv") + kDryerArx + " --trace " + Q(dir / trace), "is the input data file");
  EXPECT_EQ(ReadFile((dir / "d.csv").string()), before);
  EXPECT_TRUE(fs::is_symlink(dir / "alias.csv"));
  EXPECT_EQ(TemporaryFiles(dir), 0);
}

TEST(OutputFilesCli, ExistingTraceKeepsItsBytesWhenTheFitFails) {
  const fs::path dir = DirWithDryer("keep");
  const std::string keep = WriteFile("outputs_keep/keep", "precious, not a trace\n");
  WriteFile("outputs_keep/ragged.csv", "u,y\n1,2\n3,4\n5\n");
  ExpectCliError("fit " + Q(dir / "ragged.csv") + kDryerArx + " --trace " + Q(keep), "ragged.csv:4: row has 1 field");
  EXPECT_EQ(ReadFile(keep), "precious, not a trace\n");
  // A failure after the estimation started (an unknown column is found only when the data is read).
  ExpectCliError("fit " + Q(dir / "d.csv") + " --output nope --input u --trace " + Q(keep), "nope");
  EXPECT_EQ(ReadFile(keep), "precious, not a trace\n");
  EXPECT_EQ(TemporaryFiles(dir), 0);
}

TEST(OutputFilesCli, TraceThroughASymbolicLinkKeepsTheLinkAndTheTargetOnFailure) {
  const fs::path dir = DirWithDryer("link");
  const std::string target = WriteFile("outputs_link/target.csv", "old target\n");
  fs::create_symlink("target.csv", dir / "link.csv");
  WriteFile("outputs_link/ragged.csv", "u,y\n1,2\n3\n");
  ExpectCliError("fit " + Q(dir / "ragged.csv") + kDryerArx + " --trace " + Q(dir / "link.csv"), "row has 1 field");
  EXPECT_TRUE(fs::is_symlink(dir / "link.csv"));
  EXPECT_EQ(ReadFile(target), "old target\n");
  // A successful fit writes through the link: one row per update, the link stays.
  const CliResult r =
      RunCli("fit " + Q(dir / "d.csv") + kDryerArx + " --estimator rls --json --trace " + Q(dir / "link.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(fs::is_symlink(dir / "link.csv"));
  const io::DataTable trace = io::ReadCsv(target);
  EXPECT_EQ(trace.names.front(), "t");
  EXPECT_EQ(trace.names.back(), "Dy");
  EXPECT_EQ(trace.num_rows(), 496);  // 500 estimation rows, the first 4 without a full ARX(2,2,3) regressor
  EXPECT_EQ(trace.values(0, 0), 5);
  EXPECT_EQ(TemporaryFiles(dir), 0);
}

// The devices are private nodes in the test's directory (a program that unlinks its output on failure
// removes those, never the system's /dev/full); without the right to create one (not root), the
// directory and "-" are checked.
TEST(OutputFilesCli, DevicesDirectoriesAndStdoutAreRefusedAsOutputFiles) {
  const fs::path dir = DirWithDryer("devices");
  const fs::path full = dir / "full", null = dir / "null";
  const bool devices = mknod(full.c_str(), S_IFCHR | 0666, makedev(1, 7)) == 0 &&
                       mknod(null.c_str(), S_IFCHR | 0666, makedev(1, 3)) == 0;
  if (devices) {
    ExpectCliError("fit " + Q(dir / "d.csv") + kDryerArx + " --trace " + Q(full),
                   "cannot write --trace file '" + full.string() + "': not a regular file");
    ExpectCliError(kSmallMems + " --csv " + Q(full),
                   "cannot write --csv file '" + full.string() + "': not a regular file");
    ExpectCliError(kSmallMems + " --trace " + Q(null),
                   "cannot write --trace file '" + null.string() + "': not a regular file");
    struct stat st {};
    ASSERT_EQ(stat(full.c_str(), &st), 0);
    EXPECT_TRUE(S_ISCHR(st.st_mode));
    EXPECT_EQ(st.st_rdev, makedev(1, 7));
  }
  ExpectCliError("fit " + Q(dir / "d.csv") + kDryerArx + " --trace " + Q(dir), "not a regular file");
  ExpectCliError("fit " + Q(dir / "d.csv") + kDryerArx + " --trace -", "--trace '-': writing to standard output");
  ExpectCliError("fit " + Q(dir / "d.csv") + kDryerArx + " --trace /nonexistent-dir/t.csv",
                 "cannot write --trace file '/nonexistent-dir/t.csv': No such file or directory");
  EXPECT_FALSE(fs::exists("-"));
  EXPECT_EQ(TemporaryFiles(dir), 0);
}

TEST(OutputFilesCli, TwoOutputsNamingOneFileAreRefused) {
  const fs::path dir = DirWithDryer("two");
  const std::string x = WriteFile("outputs_two/x.csv", "x before\n");
  ExpectCliError(kSmallMems + " --csv " + Q(x) + " --trace " + Q(x), "--csv and --trace name the same file");
  EXPECT_EQ(ReadFile(x), "x before\n");
  ExpectCliError("fit " + Q(dir / "d.csv") + kDryerArx + " --trace " + Q(dir / "f.svg") + " --plot " + Q(dir / "f.svg"),
                 "--trace and --plot name the same file");
  ExpectCliError("compare " + Q(dir / "d.csv") + kDryerArx + " --plot " + Q(dir / "d.csv"), "is the input data file");
  const std::string prior = WriteFile("outputs_two/p.json", R"({"nu0": 5, "V0": [[1]]})");
  ExpectCliError("fit " + Q(dir / "d.csv") + kDryerArx + " --prior " + Q(prior) + " --trace " + Q(prior),
                 "--trace file '" + prior + "' is the --prior file '" + prior + "'; give another name");
  EXPECT_EQ(ReadFile(prior), R"({"nu0": 5, "V0": [[1]]})");
  EXPECT_FALSE(fs::exists(dir / "f.svg"));
}

TEST(OutputFilesCli, MemsWritesCompleteFilesAndPrintsAfterThem) {
  const fs::path dir = DirWithDryer("mems");
  const std::string csv = WriteFile("outputs_mems/fig9.csv", "old\n");
  const CliResult r = RunCli(kSmallMems + " --csv " + Q(csv) + " --trace " + Q(dir / "fig8.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("MEMS accelerometer"), std::string::npos);
  const io::DataTable table = io::ReadCsv(csv, {.missing_as_nan = true});  // grid_difference: none
  EXPECT_EQ(table.num_rows(), 1);
  EXPECT_EQ(table.values(0, 1), 1.0);  // t_target
  const io::DataTable trace = io::ReadCsv((dir / "fig8.csv").string());
  EXPECT_EQ(trace.num_rows(), 400);
  EXPECT_NEAR(trace.values(1, 0) - trace.values(0, 0), 0.01, 1e-12);  // t steps by h
  EXPECT_EQ(TemporaryFiles(dir), 0);
}

// A study of 4 x 10^6 steps is stopped by SIGTERM once its --csv temporary file exists (created before the
// study starts): the process dies by the signal, the existing --csv file keeps its bytes, and the
// temporary file is gone. No timing is asserted: the test waits for the file, then signals.
TEST(OutputFilesCli, SigtermDuringARunKeepsTheOutputAndRemovesTheTemporaryFile) {
  const fs::path dir = DirWithDryer("sigterm");
  const std::string csv = WriteFile("outputs_sigterm/fig9.csv", "old fig9\n");
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    if (!std::freopen("/dev/null", "w", stdout) || !std::freopen("/dev/null", "w", stderr)) _exit(126);
    execl(IDENT_CLI_PATH, "ident", "mems", "--steps", "1000000", "--grid-points", "96", "--t-mean", "1,1,1,1", "--csv",
          csv.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  bool started = false;  // the temporary file exists
  int status = 0;
  bool exited = false;
  for (int i = 0; i < 12000 && !started && !exited; ++i) {
    started = TemporaryFiles(dir) == 1;
    exited = waitpid(child, &status, WNOHANG) == child;
    if (!started && !exited) usleep(5000);
  }
  if (!exited) {
    kill(child, SIGTERM);
    ASSERT_EQ(waitpid(child, &status, 0), child);
  }
  EXPECT_TRUE(started);
  ASSERT_TRUE(WIFSIGNALED(status)) << "status " << status;
  EXPECT_EQ(WTERMSIG(status), SIGTERM);
  EXPECT_EQ(ReadFile(csv), "old fig9\n");
  EXPECT_EQ(TemporaryFiles(dir), 0);
}

// Runs `ident ARGS REDIRECTION` through sh; returns the exit code, stderr in `err`.
int RunWithStdout(const std::string& args, const std::string& redirection, std::string& err) {
  const std::string err_file = TempDir() + "/stdout_test.err";
  const std::string command =
      std::string("'") + IDENT_CLI_PATH + "' " + args + " " + redirection + " 2> '" + err_file + "' < /dev/null";
  const int status = std::system(command.c_str());
  err = ReadFile(err_file);
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

void ExpectStdoutError(const std::string& args, const std::string& redirection, const std::string& reason) {
  std::string err;
  EXPECT_EQ(RunWithStdout(args, redirection, err), 1) << args << " " << redirection << "\n" << err;
  // A run longer than 2 s (a sanitizer build) reports progress on stderr first; the error is the last line.
  const std::string expected = "ident: error: cannot write to standard output: " + reason + "\n";
  ASSERT_GE(err.size(), expected.size()) << err;
  EXPECT_EQ(err.substr(err.size() - expected.size()), expected) << args << " " << redirection;
  std::istringstream before(err.substr(0, err.size() - expected.size()));
  for (std::string line; std::getline(before, line);)
    EXPECT_TRUE(line.rfind("ident ", 0) == 0 && line.find(" % (") != std::string::npos)
        << "not a progress line: " << line;
}

TEST(OutputFilesCli, FullStandardOutputIsAnError) {
  const std::string dryer = DatasetPath("dryer.csv");
  ExpectStdoutError("fit '" + dryer + "'" + kDryerArx + " --json", ">/dev/full", "No space left on device");
  ExpectStdoutError("fit '" + dryer + "'" + kDryerArx, ">/dev/full", "No space left on device");
  ExpectStdoutError("datasets --json", ">/dev/full", "No space left on device");
  ExpectStdoutError(kSmallMems, ">/dev/full", "No space left on device");
  ExpectStdoutError("--help", ">/dev/full", "No space left on device");
}

TEST(OutputFilesCli, ClosedStandardOutputIsAnError) {
  const std::string dryer = DatasetPath("dryer.csv");
  ExpectStdoutError("fit '" + dryer + "'" + kDryerArx + " --json", ">&-", "Bad file descriptor");
  ExpectStdoutError("datasets", ">&-", "Bad file descriptor");
  // With stdout closed, the trace file still gets the trace, not the report.
  const fs::path dir = DirWithDryer("closed");
  ExpectStdoutError("fit " + Q(dir / "d.csv") + kDryerArx + " --trace " + Q(dir / "t.csv"), ">&-",
                    "Bad file descriptor");
  EXPECT_EQ(ReadFile((dir / "t.csv").string()).rfind("t,nu,beta,pred_err,", 0), 0u);
  EXPECT_EQ(io::ReadCsv((dir / "t.csv").string()).num_rows(), 496);
}

TEST(OutputFilesCli, WorkingStandardOutputExitsZero) {  // the check itself does not fail a good run
  std::string err;
  EXPECT_EQ(RunWithStdout("datasets --json", ">/dev/null", err), 0) << err;
  EXPECT_EQ(err, "");
}

}  // namespace
}  // namespace ident::testing
