// ident stream: rows written into a FIFO come back as JSON lines while the writer still holds it open,
// and the estimate after the last row is `ident fit --split 1 --detrend none`'s on the same rows, bit for
// bit (RLS: `fit --exact`, whose flat prior is the stream's). Bad rows: one line with the line and the
// data row, a non-zero exit, the lines of the rows before it printed.
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cmath>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "tests/support/cli.h"

extern char** environ;

namespace ident::testing {
namespace {

// A deadlock guard, not a timing assertion: a missing line fails the test instead of hanging it.
constexpr int kPatienceMs = 120'000;

// y(t) = 1.2 y(t−1) − 0.5 y(t−2) + 0.8 u(t−1) + 0.3 u(t−2) + e(t), e Gaussian (σ 0.1) with a gross
// outlier (+40) at row `outlier_row` (1-based; 0: none); x, a static regressor, is u.
std::vector<std::string> StreamRows(int n, int outlier_row = 0) {
  std::mt19937 rng(11);
  std::normal_distribution<double> normal;
  std::vector<double> u(n), y(n, 0.0);
  for (int t = 0; t < n; ++t) u[t] = normal(rng);
  std::vector<std::string> rows;
  for (int t = 0; t < n; ++t) {
    if (t >= 2) y[t] = 1.2 * y[t - 1] - 0.5 * y[t - 2] + 0.8 * u[t - 1] + 0.3 * u[t - 2] + 0.1 * normal(rng);
    const double measured = y[t] + (t + 1 == outlier_row ? 40.0 : 0.0);
    rows.push_back(fmt::format("{},{},{}", u[t], measured, 2.0 + 0.5 * u[t] + 0.1 * normal(rng)));
  }
  return rows;
}

std::string StreamCsv(const std::vector<std::string>& rows, std::size_t count) {
  std::string text = "u,y,x\n";
  for (std::size_t i = 0; i < count; ++i) text += rows[i] + "\n";
  return text;
}

std::vector<nlohmann::json> StreamLines(const std::string& out) {
  std::vector<nlohmann::json> lines;
  for (std::size_t start = 0; start < out.size();) {
    const std::size_t end = out.find('\n', start);
    lines.push_back(nlohmann::json::parse(out.substr(start, end - start)));
    start = end == std::string::npos ? out.size() : end + 1;
  }
  return lines;
}

std::vector<double> StreamFitTheta(const std::string& csv_path, const std::string& options) {
  const CliResult r = RunCli("fit '" + csv_path + "' " + options + " --split 1 --detrend none --json");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  return nlohmann::json::parse(r.out)["theta"].get<std::vector<double>>();
}

// `ident stream FIFO ARGS` with its standard output on a pipe that the test reads.
class StreamProcess {
 public:
  StreamProcess(const std::string& fifo, const std::vector<std::string>& args) {
    signal(SIGPIPE, SIG_IGN);  // a program that died makes Write fail, not the test
    int out[2];
    EXPECT_EQ(pipe(out), 0);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_adddup2(&actions, out[1], 1);
    posix_spawn_file_actions_addclose(&actions, out[0]);
    std::vector<std::string> argv_strings = {IDENT_CLI_PATH, "stream", fifo};
    argv_strings.insert(argv_strings.end(), args.begin(), args.end());
    std::vector<char*> argv;
    for (std::string& s : argv_strings) argv.push_back(s.data());
    argv.push_back(nullptr);
    EXPECT_EQ(posix_spawn(&pid_, IDENT_CLI_PATH, &actions, nullptr, argv.data(), environ), 0);
    posix_spawn_file_actions_destroy(&actions);
    close(out[1]);
    out_ = out[0];
    // The FIFO's writer end: open(2) without O_NONBLOCK would wait for ever if the program never opened it.
    for (int waited = 0; writer_ < 0 && waited < kPatienceMs; waited += 10) {
      writer_ = open(fifo.c_str(), O_WRONLY | O_NONBLOCK | O_CLOEXEC);
      if (writer_ < 0) std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    EXPECT_GE(writer_, 0) << "the program did not open the FIFO";
    if (writer_ >= 0) fcntl(writer_, F_SETFL, fcntl(writer_, F_GETFL) & ~O_NONBLOCK);
  }
  ~StreamProcess() {
    if (writer_ >= 0) close(writer_);
    if (out_ >= 0) close(out_);
    if (pid_ > 0 && !waited_) {
      kill(pid_, SIGKILL);
      waitpid(pid_, nullptr, 0);
    }
  }

  void Write(const std::string& text) {
    ASSERT_EQ(write(writer_, text.data(), text.size()), static_cast<ssize_t>(text.size()));
  }
  void CloseWriter() {
    close(writer_);
    writer_ = -1;
  }
  // Reads until `lines` complete lines have come (or the output ends); returns them.
  std::vector<nlohmann::json> ReadLines(std::size_t lines) {
    std::vector<nlohmann::json> got;
    while (got.size() < lines) {
      const std::size_t end = pending_.find('\n');
      if (end != std::string::npos) {
        got.push_back(nlohmann::json::parse(pending_.substr(0, end)));
        pending_.erase(0, end + 1);
        continue;
      }
      pollfd p{out_, POLLIN, 0};
      if (poll(&p, 1, kPatienceMs) <= 0) {
        ADD_FAILURE() << "no output line within the patience limit after " << got.size() << " of " << lines;
        break;
      }
      char buffer[4096];
      const ssize_t n = read(out_, buffer, sizeof buffer);
      if (n <= 0) break;
      pending_.append(buffer, static_cast<std::size_t>(n));
    }
    return got;
  }
  int Wait() {
    int status = 0;
    waitpid(pid_, &status, 0);
    waited_ = true;
    return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  }

 private:
  pid_t pid_ = -1;
  int out_ = -1, writer_ = -1;
  bool waited_ = false;
  std::string pending_;
};

void StreamThroughFifo(const std::string& flush_option) {
  const int n = 300, outlier = 150;
  const std::vector<std::string> rows = StreamRows(n, outlier);
  const std::string fifo = TempDir() + "/rows" + flush_option + ".fifo";
  unlink(fifo.c_str());
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  std::vector<std::string> args = {"--output", "y", "--input", "u", "--na",        "2",
                                   "--nb",     "2", "--nk",    "1", "--estimator", "cauchy"};
  if (!flush_option.empty()) args.insert(args.end(), {"--flush-every", flush_option});
  StreamProcess stream(fifo, args);
  stream.Write("u,y,x\n");
  // Rows in batches of 1, 2, 3, ...: each batch's lines arrive before the next batch is written.
  std::vector<nlohmann::json> lines;
  for (int written = 0, batch = 1; written < n; written += batch, ++batch) {
    const int count = std::min(batch, n - written);
    std::string text;
    for (int i = 0; i < count; ++i) text += rows[static_cast<std::size_t>(written + i)] + "\n";
    stream.Write(text);
    const std::vector<nlohmann::json> got = stream.ReadLines(static_cast<std::size_t>(count));
    ASSERT_EQ(got.size(), static_cast<std::size_t>(count)) << "after row " << written;
    for (int i = 0; i < count; ++i) EXPECT_EQ(got[static_cast<std::size_t>(i)]["t"], written + i + 1);
    lines.insert(lines.end(), got.begin(), got.end());
  }
  stream.CloseWriter();
  const std::vector<nlohmann::json> rest = stream.ReadLines(2);  // an "end" line if the end steps moved θ
  EXPECT_EQ(stream.Wait(), 0);
  ASSERT_LE(rest.size(), 1u);
  for (const nlohmann::json& line : rest) EXPECT_EQ(line["status"], "end");
  lines.insert(lines.end(), rest.begin(), rest.end());

  // The regressor's first t0 = 2 rows and the start window are start-up; the outlier is flagged.
  EXPECT_EQ(lines[0]["status"], "start-up");
  EXPECT_TRUE(lines[0]["weight"].is_null());
  EXPECT_EQ(lines[static_cast<std::size_t>(outlier - 1)]["status"], "outlier");
  EXPECT_LT(lines[static_cast<std::size_t>(outlier - 1)]["weight"].get<double>() *
                lines[static_cast<std::size_t>(outlier - 1)]["nu"].get<double>(),
            0.2);
  int ok = 0;
  for (const nlohmann::json& line : lines) ok += line["status"] == "ok";
  EXPECT_GT(ok, n / 2);

  const std::string csv = WriteFile("fifo_rows.csv", StreamCsv(rows, rows.size()));
  const std::vector<double> fit = StreamFitTheta(csv, "--output y --input u --na 2 --nb 2 --nk 1 --estimator cauchy");
  EXPECT_EQ(lines.back()["theta"].get<std::vector<double>>(), fit);  // bit for bit
  // ... and near the system's (a sanity check that the numbers are the model's).
  const std::vector<double> truth = {-1.2, 0.5, 0.8, 0.3};
  for (std::size_t i = 0; i < truth.size(); ++i) EXPECT_NEAR(fit[i], truth[i], 0.1);
}

TEST(Stream, FifoLinesArriveBeforeTheWriterClosesAndEndAtFitsEstimate) { StreamThroughFifo(""); }

TEST(Stream, WithoutPerLineFlushLinesStillArriveBeforeTheProgramWaits) { StreamThroughFifo("0"); }

TEST(Stream, RlsAtEveryRowIsTheExactFitOfTheRowsSoFar) {
  const std::vector<std::string> rows = StreamRows(200);
  const std::string arx = "--output y --input u --na 2 --nb 2 --nk 1 --estimator rls --forgetting 0.98";
  const CliResult r = RunCli("stream '" + WriteFile("rls_rows.csv", StreamCsv(rows, rows.size())) + "' " + arx);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::vector<nlohmann::json> lines = StreamLines(r.out);
  ASSERT_EQ(lines.size(), rows.size());  // RLS has no end-of-data step
  for (std::size_t k : {20u, 77u, 200u}) {
    const std::string part = WriteFile(fmt::format("rls_first_{}.csv", k), StreamCsv(rows, k));
    EXPECT_EQ(lines[k - 1]["theta"].get<std::vector<double>>(), StreamFitTheta(part, arx + " --exact")) << "row " << k;
    EXPECT_EQ(lines[k - 1]["status"], "ok");
    EXPECT_NEAR(lines[k - 1]["weight"].get<double>() * lines[k - 1]["nu"].get<double>(), 1.0, 1e-12);  // β = 1/ν
  }
}

TEST(Stream, StaticRegressionWithInterceptIsFitsWithoutDetrending) {
  const std::vector<std::string> rows = StreamRows(120);
  const std::string path = WriteFile("static_rows.csv", StreamCsv(rows, rows.size()));
  const std::string model = "--output x --regressors u --intercept --estimator student:3";
  const CliResult r = RunCli("stream '" + path + "' " + model);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::vector<nlohmann::json> lines = StreamLines(r.out);
  const std::vector<double> theta = lines.back()["theta"].get<std::vector<double>>();
  EXPECT_EQ(theta, StreamFitTheta(path, model));
  EXPECT_NEAR(theta[0], 2.0, 0.05);  // x = 2 + 0.5 u + noise
  EXPECT_NEAR(theta[1], 0.5, 0.05);
}

TEST(Stream, MissingSamplesAreReportedAndSkippedAsFitSkipsThem) {
  std::vector<std::string> rows = StreamRows(200);
  rows[99] = rows[99].substr(0, rows[99].find(',')) + ",," + rows[99].substr(rows[99].rfind(',') + 1);  // y empty
  const std::string path = WriteFile("missing_rows.csv", StreamCsv(rows, rows.size()));
  const std::string arx = "--output y --input u --na 2 --nb 2 --nk 1 --estimator cauchy --missing";
  const CliResult r = RunCli("stream '" + path + "' " + arx);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::vector<nlohmann::json> lines = StreamLines(r.out);
  // Row 100 has no y; rows 101 and 102 regress on it: three rows without an update, θ unchanged.
  for (std::size_t row : {100u, 101u, 102u}) {
    EXPECT_EQ(lines[row - 1]["status"], "missing") << row;
    EXPECT_EQ(lines[row - 1]["theta"], lines[98]["theta"]) << row;
  }
  EXPECT_NE(lines[102]["status"], "missing");
  EXPECT_EQ(lines.back()["theta"].get<std::vector<double>>(), StreamFitTheta(path, arx));
}

TEST(Stream, BadRowsAndOptionsAreOneLineErrors) {
  std::vector<std::string> rows = StreamRows(10);
  rows[4] = "1.5,abc,2";
  const std::string bad = WriteFile("bad_rows.csv", StreamCsv(rows, rows.size()));
  const std::string arx = " --output y --input u --na 1 --nb 1 --nk 1";
  const CliResult r = RunCli("stream '" + bad + "'" + arx);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(r.err, "ident: error: " + bad + ":6: column 2 ('y'): 'abc' is not a number (data row 5)\n");
  EXPECT_EQ(StreamLines(r.out).size(), 4u);  // the rows before it were reported
  ExpectCliError("stream '" + WriteFile("short_row.csv", "u,y\n3\n1,2\n") + "'" + arx,
                 "short_row.csv:2: row has 1 field; the header has 2 (data row 1)");
  ExpectCliError("stream '" + WriteFile("header_only.csv", "u,y\n") + "'" + arx, "no data rows after the header");
  ExpectCliError("stream '" + bad + "'" + arx + " --estimator huber", "'huber' is a batch estimator");
  ExpectCliError("stream '" + bad + "' --output q --input u", "no column 'q'");
  ExpectCliError("stream '" + bad + "'" + arx + " --estimator nosuch", "nosuch");
  ExpectCliError("stream '" + bad + "'" + arx + " --flush-every -1", "--flush-every -1");
  ExpectCliError("stream " + TempDir() + "/absent.csv" + arx, "cannot open");
  ExpectCliError("stream '" + bad + "' --input u", "--output", 2);
}

}  // namespace
}  // namespace ident::testing
