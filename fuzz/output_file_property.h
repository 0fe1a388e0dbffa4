// Property of the output-file writer (ident::cli::OutputFile) and the trace row writer of `ident fit`
// (ident::workflow::WriteTraceRow), on arbitrary content, chunking and failure points.
// Input:
//   1 byte flags: bit 0 the target exists before (old content), bit 1 the target is a symbolic link to
//     the file, bits 2-3 the failure (0 none, 1 abandoned before Commit at the failure point, 2 the
//     process's file size limit set to the failure point, so a write, flush or close fails with EFBIG,
//     3 = 0), bit 4 trace mode;
//   1 byte n, then n bytes: the old content;
//   2 bytes: the failure point (bytes, little-endian);
//   the rest: raw mode: chunks (1 byte length L, 1 byte repeat r, L bytes; the chunk is the L bytes
//     r + 1 times), written with Write(); trace mode: 1 byte ρ (1..6), then rows of ρ + 4 raw doubles
//     (ν, β, prediction error, θ, Dy), written with WriteTraceRow to stream().
// Holds if:
//   the run commits exactly when it is neither abandoned nor beyond the file size limit (a write error
//   is never ignored); after it the target holds the complete new content (committed) or its old content
//   byte for byte (else; absent if there was none); a symbolic link stays a link to the same file; no
//   temporary file remains in the directory and the signal handler's table is empty;
//   trace mode, committed with at least one row: the file reads back (ident/io/csv.h, missing_as_nan)
//   to the header's columns and every finite number bit for bit, every NaN/±Inf as NaN.
// Each input runs in a fresh directory under /dev/shm (else the system temp directory), removed afterwards.
#pragma once

#include <signal.h>
#include <stdlib.h>
#include <sys/resource.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "cli/output_file.h"
#include "common/error.h"
#include "fuzz/fuzz_util.h"
#include "ident/io/csv.h"
#include "ident/workflow/fit.h"

namespace ident::fuzz {

namespace output_file_detail {

inline std::optional<std::string> Slurp(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return std::nullopt;
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

// Sets the soft file size limit (and ignores SIGXFSZ, so a write beyond it fails with EFBIG instead of
// killing the process) for its lifetime.
class FileSizeLimit {
 public:
  explicit FileSizeLimit(rlim_t bytes) {
    getrlimit(RLIMIT_FSIZE, &saved_);
    struct sigaction ignore {};
    ignore.sa_handler = SIG_IGN;
    sigemptyset(&ignore.sa_mask);
    sigaction(SIGXFSZ, &ignore, &saved_action_);
    rlimit limit = saved_;
    limit.rlim_cur = bytes;
    if (saved_.rlim_max != RLIM_INFINITY && bytes > saved_.rlim_max) limit.rlim_cur = saved_.rlim_max;
    setrlimit(RLIMIT_FSIZE, &limit);
  }
  ~FileSizeLimit() {
    setrlimit(RLIMIT_FSIZE, &saved_);
    sigaction(SIGXFSZ, &saved_action_, nullptr);
  }
  FileSizeLimit(const FileSizeLimit&) = delete;
  FileSizeLimit& operator=(const FileSizeLimit&) = delete;

 private:
  rlimit saved_{};
  struct sigaction saved_action_ {};
};

struct Abandon {};  // thrown to leave the writing scope before Commit, as an error in a command does

}  // namespace output_file_detail

inline std::string OutputFileProperty(const std::uint8_t* data, std::size_t size) {
  namespace fs = std::filesystem;
  using namespace output_file_detail;
  ByteReader in(data, size);
  const std::uint8_t flags = in.Byte();
  const bool existed = (flags & 1) != 0, via_link = (flags & 2) != 0, trace_mode = (flags & 16) != 0;
  const int failure = (flags >> 2) & 3;
  std::string old_content(in.Byte(), '\0');
  for (char& c : old_content) c = static_cast<char>(in.Byte());
  const std::size_t fail_at = in.Byte() | (std::size_t{in.Byte()} << 8);

  // The new content, as chunks (raw mode) or rows (trace mode), and its expected bytes.
  std::vector<std::string> chunks;
  std::vector<std::vector<double>> rows;  // ν, β, e, θ..., Dy
  int rho = 0;
  std::string expected;
  if (!trace_mode) {
    while (in.remaining() > 0) {
      const std::size_t length = in.Byte(), repeat = 1 + std::size_t{in.Byte()};
      std::string piece;
      for (std::size_t i = 0; i < length; ++i) piece += static_cast<char>(in.Byte());
      std::string chunk;
      for (std::size_t r = 0; r < repeat; ++r) chunk += piece;
      expected += chunk;
      chunks.push_back(std::move(chunk));
    }
  } else {
    rho = 1 + in.Byte() % 6;
    while (in.remaining() >= 8 * static_cast<std::size_t>(rho + 4)) {
      std::vector<double> row(static_cast<std::size_t>(rho + 4));
      for (double& v : row) v = in.Double();
      rows.push_back(std::move(row));
    }
    char* buffer = nullptr;
    std::size_t buffer_size = 0;
    std::FILE* memory = open_memstream(&buffer, &buffer_size);
    if (!memory) return {};  // out of memory: nothing to check
    workflow::WriteTraceHeader(memory, rho);
    for (std::size_t k = 0; k < rows.size(); ++k) {
      const std::vector<double>& r = rows[k];
      const Eigen::VectorXd theta = Eigen::Map<const Eigen::VectorXd>(r.data() + 3, rho);
      workflow::WriteTraceRow(memory, {.t = static_cast<long>(k + 1),
                                       .nu = r[0],
                                       .beta = r[1],
                                       .pred_err = r[2],
                                       .theta = &theta,
                                       .Dy = r[static_cast<std::size_t>(rho) + 3]});
    }
    std::fclose(memory);
    expected.assign(buffer, buffer_size);
    std::free(buffer);
  }

  // Memory-backed /dev/shm where there is one: the fsync of every commit costs nothing there.
  std::error_code shm_error;
  const fs::path base = fs::is_directory("/dev/shm", shm_error) ? fs::path("/dev/shm") : fs::temp_directory_path();
  std::string dir_pattern = (base / "ident-outfuzz-XXXXXX").string();
  if (!mkdtemp(dir_pattern.data())) return {};  // no temp directory: nothing to check
  const fs::path dir = dir_pattern;
  const fs::path file = dir / "out.csv", link = dir / "link.csv";
  const fs::path target = via_link ? link : file;
  std::string violated;
  auto check = [&violated](bool ok, const char* what) {
    if (!ok && violated.empty()) violated = what;
  };
  if (existed) std::ofstream(file, std::ios::binary) << old_content;
  std::error_code ec;
  if (via_link) fs::create_symlink("out.csv", link, ec);

  bool committed = false, refused = false;
  try {
    cli::OutputFile out(target.string(), "fuzz file");
    std::size_t written = 0;
    std::optional<FileSizeLimit> limit;
    if (failure == 2) limit.emplace(static_cast<rlim_t>(fail_at));
    if (!trace_mode) {
      for (const std::string& chunk : chunks) {
        if (failure == 1 && written + chunk.size() > fail_at) throw Abandon{};
        out.Write(chunk);
        written += chunk.size();
      }
    } else {
      workflow::WriteTraceHeader(out.stream(), rho);
      for (std::size_t k = 0; k < rows.size(); ++k) {
        if (failure == 1 && k >= fail_at % 64) throw Abandon{};
        const std::vector<double>& r = rows[k];
        const Eigen::VectorXd theta = Eigen::Map<const Eigen::VectorXd>(r.data() + 3, rho);
        workflow::WriteTraceRow(out.stream(), {.t = static_cast<long>(k + 1),
                                               .nu = r[0],
                                               .beta = r[1],
                                               .pred_err = r[2],
                                               .theta = &theta,
                                               .Dy = r[static_cast<std::size_t>(rho) + 3]});
      }
    }
    if (failure == 1) throw Abandon{};
    out.Commit();
    committed = true;
  } catch (const Abandon&) {
  } catch (const InvalidArgument&) {
    refused = true;
  }

  check(!(failure == 1 && committed), "an abandoned file is not committed");
  if (failure == 2)
    check(committed == (expected.size() <= fail_at), "a write beyond the size limit fails, else commits");
  if (failure == 0) check(committed, "a run without failure commits");
  check(committed || failure != 0 || refused, "a run ends committed, abandoned or refused");
  const std::optional<std::string> now = Slurp(file);
  if (committed)
    check(now && *now == expected, "a committed target holds the complete new content");
  else if (existed)
    check(now && *now == old_content, "a failed run leaves the old content byte for byte");
  else
    check(!now, "a failed run creates no target");
  if (via_link) check(fs::is_symlink(link) && fs::read_symlink(link) == "out.csv", "a symbolic link stays a link");
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    const std::string name = entry.path().filename().string();
    check(name == "out.csv" || name == "link.csv", "no temporary file remains");
  }
  check(cli::PendingOutputFiles() == 0, "the signal handler's table is empty");

  if (trace_mode && committed && !rows.empty() && violated.empty()) {
    try {
      const io::DataTable table = io::ReadCsv(file.string(), {.missing_as_nan = true});
      check(table.values.cols() == rho + 5 && table.num_rows() == static_cast<int>(rows.size()),
            "the trace reads back with its rows and columns");
      check(table.names.front() == "t" && table.names.back() == "Dy", "the header names t first and Dy last");
      if (violated.empty()) {
        for (int k = 0; k < table.num_rows(); ++k) {
          check(table.values(k, 0) == k + 1, "t reads back");
          const std::vector<double>& r = rows[static_cast<std::size_t>(k)];
          for (int c = 0; c < rho + 4; ++c) {
            const double written = r[static_cast<std::size_t>(c)], read = table.values(k, c + 1);
            if (std::isfinite(written))
              check(std::memcmp(&written, &read, sizeof read) == 0, "a finite number reads back bit for bit");
            else
              check(std::isnan(read), "NaN and Inf read back as missing");
          }
        }
      }
    } catch (const DataError&) {
      check(false, "the trace reads back without error");
    }
  }
  fs::remove_all(dir, ec);
  return violated;
}

}  // namespace ident::fuzz
