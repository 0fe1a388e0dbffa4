// Properties of the whole command line, run in-process through cli::RunCommandLine: the fuzzer's bytes
// choose a small data file (raw bytes, or rows of numbers and odd tokens) and an argument vector
// (subcommand fit, compare, smooth, logcondens or datasets, options and values from vocabularies that
// include the limits and the bad values; `mems` on a small study). For every input:
//   - the exit code is 0 (success), 1 (bad data or options) or 2 (usage error);
//   - a failed run prints exactly one line "ident: error: <message>" on std::cerr;
//   - the data file and the model file are byte for byte what they were (no input is modified);
//   - no temporary output file is left behind, and a --trace file exists only after a successful run;
//   - what a successful run writes reads back: --json output is one JSON document; compare --csv output
//     is a header starting "estimator" and rows of as many fields; the mems --csv and --trace files read
//     with ident's CSV reader (ident/io/csv.h), which takes only finite numbers.
// IDENT_CLI_FUZZ_LOG=1 prints each call, its exit code and its error line.
// Standard output is captured during the run: descriptor 1 (fmt::print, printf) to a file in the run's
// directory, std::cout to a string; what a run printed is the two together.
#pragma once

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "cli/command_line.h"
#include "common/error.h"
#include "fuzz/fuzz_util.h"
#include "ident/io/csv.h"

namespace ident::fuzz {

namespace cli_internal {

inline const std::string& Dir() {
  static const ScratchDir dir("ident-cli-fuzz-");
  return dir.path();
}

inline std::string Slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

inline void Spit(const std::string& path, const std::string& text) {
  std::ofstream(path, std::ios::binary | std::ios::trunc) << text;
}

template <std::size_t N>
const char* Pick(ByteReader& in, const char* const (&list)[N]) {
  return list[in.Byte() % N];
}

// Cells: ordinary numbers most of the time, then the tokens the reader must refuse or treat as missing.
inline std::string Cell(ByteReader& in) {
  static const char* const kOdd[] = {"nan", "", "1e308", "-1.7e308", "1e-320", "+-5", "inf", "x", " 3 ", "1e309"};
  const std::uint8_t b = in.Byte();
  if (b != 255 || in.Byte() % 4 != 0)
    return std::to_string(static_cast<int>(static_cast<std::int8_t>(in.Byte())) / 16.0 + (b % 7) * 0.1);
  return Pick(in, kOdd);
}

inline std::string DataFile(ByteReader& in) {
  const std::uint8_t mode = in.Byte();
  std::string text;
  if (mode % 4 == 0) {  // raw bytes
    const std::size_t n = in.Byte() * 2u;
    for (std::size_t i = 0; i < n && in.remaining() > 0; ++i) text += static_cast<char>(in.Byte());
    return text;
  }
  static const char* const kHeaders[] = {"u,x,y,z", "u,y", "y,u,u", "t,u,y,z,x"};
  const std::string header = Pick(in, kHeaders);
  const int columns = static_cast<int>(std::count(header.begin(), header.end(), ',')) + 1;
  const int rows = 2 + in.Byte() % 80;
  text = header + "\n";
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < columns; ++c) {
      // A smooth record: sin/cos plus the byte-chosen cell as noise, so fits usually succeed.
      const std::string cell = Cell(in);
      const double smooth = (c + 1) * std::sin(0.3 * r + c);
      text += (c ? "," : "") + (cell.find_first_of("0123456789") == 0 || cell.rfind('-', 0) == 0
                                    ? std::to_string(smooth + std::atof(cell.c_str()) * 0.1)
                                    : cell);
    }
    text += (in.Byte() % 64 == 0 ? "\r\n" : "\n");
  }
  return text;
}

inline std::string ModelFile(ByteReader& in) {
  static const char* const kMeasurement[] = {
      R"({"penalty": "l1"})",
      R"({"penalty": "huber", "kappa": 1})",
      R"({"penalty": "piecewise_linear", "knots": [-1000, 0, 1000], "values": [1000, 0, 1000]})",
      R"({"penalty": "box", "lower": [-1], "upper": [1], "M": [[1]]})",
      R"({"penalty": "quadratic", "covariance": [[0]]})",
      R"({"penalty": "vapnik", "epsilon": 0.1})"};
  static const char* const kProcess[] = {R"({"penalty": "quadratic", "covariance": [[0.1]]})",
                                         R"({"penalty": "huber", "kappa": 0.5})", R"({"penalty": "l1"})"};
  return std::string(R"({"F": [[1]], "H": [[1]], "initial": {"penalty": "quadratic", "covariance": [[1]]}, )") +
         R"("process": )" + Pick(in, kProcess) + R"(, "measurement": )" + Pick(in, kMeasurement) + "}";
}

}  // namespace cli_internal

// "" if `text` is a header whose first field is `first` and at least one row, all with as many
// comma-separated fields.
inline std::string CsvTableShape(const std::string& text, const std::string& first) {
  std::istringstream lines(text);
  std::string line;
  long fields = -1, rows = 0;
  while (std::getline(lines, line)) {
    const long n = 1 + std::count(line.begin(), line.end(), ',');
    if (fields < 0) {
      if (line.rfind(first + ",", 0) != 0) return "header does not start with '" + first + ",'";
      fields = n;
    } else if (n != fields) {
      return "a row has " + std::to_string(n) + " fields, the header " + std::to_string(fields);
    } else {
      ++rows;
    }
  }
  return rows > 0 ? "" : "no rows";
}

inline std::string CliProperty(const std::uint8_t* data, std::size_t size) {
  using namespace cli_internal;
  ByteReader in(data, size);
  const std::string dir = Dir(), data_path = dir + "/d.csv", model_path = dir + "/m.json",
                    trace_path = dir + "/trace.csv";
  const std::string data_text = DataFile(in), model_text = ModelFile(in);
  Spit(data_path, data_text);
  Spit(model_path, model_text);
  std::filesystem::remove(trace_path);

  static const char* const kCommands[] = {"fit",    "fit",        "fit",      "compare", "compare",
                                          "smooth", "logcondens", "datasets", "mems"};
  static const char* const kValues[] = {"0",     "1",   "2",   "3",   "-1", "0.5",        "0.99", "1e-300",
                                        "1e300", "nan", "inf", "abc", "",   "2147483647", "1e80", "0.2",
                                        "5",     "u",   "y",   "x",   "z",  "q",          "mean", "none"};
  static const char* const kEstimators[] = {"rls",         "cauchy",    "student:3",   "huber",
                                            "cauchy-ml",   "student",   "nonesuch",    "rls,cauchy",
                                            "rls,,cauchy", "student:0", "cauchy,huber"};
  static const char* const kFitOptions[] = {"--output",
                                            "--input",
                                            "--regressors",
                                            "--na",
                                            "--nb",
                                            "--nk",
                                            "--estimator",
                                            "--dof",
                                            "--delta",
                                            "--forgetting",
                                            "--split",
                                            "--detrend",
                                            "--missing",
                                            "--json",
                                            "--passes",
                                            "--intercept",
                                            "--nu0",
                                            "--vy0",
                                            "--vz0",
                                            "--lock-in-window",
                                            "--lock-in-threshold",
                                            "--clean-regressors",
                                            "--exact",
                                            "--trace",
                                            "--stabilised",
                                            "--estimators",
                                            "--outliers",
                                            "--trials",
                                            "--csv",
                                            "--column",
                                            "--bogus"};
  static const char* const kMemsOptions[] = {"--t-mean", "--seed",  "--h",           "--ep-window", "--csv",
                                             "--trace",  "--steps", "--grid-points", "--t-mean",    "--bogus"};
  const std::string command = Pick(in, kCommands);
  const std::string mems_csv = dir + "/mems.csv";
  std::filesystem::remove(mems_csv);
  std::vector<std::string> args = {"ident", command};
  if (command == "smooth") args.insert(args.end(), {"--model", model_path});
  if (command != "datasets" && command != "mems") args.push_back(data_path);
  if (command == "mems") {  // a small study (100 steps, the 16² grid without the refinement check: milliseconds,
                            // also under the sanitizers); sizes drawn below are refused
    args.insert(args.end(), {"--steps", "100", "--grid-points", "16", "--grid-tolerance", "0", "--t-mean", "0.5"});
    const int mems_options = in.Byte() % 5;
    for (int i = 0; i < mems_options; ++i) {
      const std::string option = Pick(in, kMemsOptions);
      args.push_back(option);
      args.push_back(option == "--csv" ? mems_csv : option == "--trace" ? trace_path : Pick(in, kValues));
    }
  }
  if (command == "fit" || command == "compare") args.insert(args.end(), {"--output", "y", "--input", "u"});
  if (command == "compare") args.insert(args.end(), {"--trials", "1", "--estimators", "rls"});
  const int options = command == "mems" ? 0 : in.Byte() % 9;
  for (int i = 0; i < options; ++i) {
    const std::string option = Pick(in, kFitOptions);
    args.push_back(option);
    if (option == "--missing" || option == "--json" || option == "--intercept" || option == "--exact" ||
        option == "--stabilised" || option == "--csv")
      continue;
    if (option == "--trace") {
      args.push_back(trace_path);
    } else if (option == "--estimator" || option == "--estimators") {
      args.push_back(Pick(in, kEstimators));
    } else if (option == "--outliers") {
      args.push_back(std::string(Pick(in, kValues)) + ":" + Pick(in, kValues));
    } else if (option == "--trials" || option == "--passes") {
      args.push_back(std::to_string(in.Byte() % 4));  // small: the fuzzer must stay fast
    } else {
      args.push_back(Pick(in, kValues));
    }
  }
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);

  std::ostringstream err, out;
  std::fflush(stdout);
  const std::string stdout_path = dir + "/stdout.txt";
  const int saved_stdout = dup(1), captured = open(stdout_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
  dup2(captured, 1);  // descriptor 1 to the file meanwhile
  close(captured);
  std::streambuf* const old_err = std::cerr.rdbuf(err.rdbuf());
  std::streambuf* const old_out = std::cout.rdbuf(out.rdbuf());
  const int code = cli::RunCommandLine(static_cast<int>(args.size()), argv.data());
  std::cerr.rdbuf(old_err);
  std::cout.rdbuf(old_out);
  std::fflush(stdout);
  std::clearerr(stdout);
  dup2(saved_stdout, 1);
  close(saved_stdout);
  const std::string printed = out.str() + Slurp(stdout_path);

  std::string call;
  for (const std::string& a : args) call += " " + a;
  if (std::getenv("IDENT_CLI_FUZZ_LOG"))  // what each input ran: IDENT_CLI_FUZZ_LOG=1 build-fuzz/fuzz/cli_fuzzer FILE
    std::fprintf(stderr, "exit %d:%s\n  %s", code, call.c_str(), err.str().empty() ? "\n" : err.str().c_str());
  if (code != 0 && code != 1 && code != 2) return "exit code " + std::to_string(code) + ":" + call;
  const std::string e = err.str();
  if (code != 0) {
    if (e.rfind("ident: error: ", 0) != 0) return "error without 'ident: error: ':" + call + " -> " + e;
    if (e.find('\n') != e.size() - 1) return "error not one line:" + call + " -> " + e;
  }
  if (Slurp(data_path) != data_text) return "data file modified:" + call;
  if (Slurp(model_path) != model_text) return "model file modified:" + call;
  for (const auto& entry : std::filesystem::directory_iterator(dir))
    if (entry.path().filename().string().find(".tmp-") != std::string::npos)
      return "temporary file left: " + entry.path().string() + ":" + call;
  if (code != 0 && std::filesystem::exists(trace_path)) return "trace written by a failed run:" + call;
  if (code != 0) return "";
  auto has = [&](const char* option) { return std::find(args.begin(), args.end(), option) != args.end(); };
  if (has("--json") && !nlohmann::json::accept(printed)) return "--json output is not one JSON document:" + call;
  if (command == "compare" && has("--csv"))
    if (std::string bad = CsvTableShape(printed, "estimator"); !bad.empty())
      return "compare --csv output: " + bad + ":" + call;
  if (command == "mems")
    for (const std::string& file : {mems_csv, trace_path}) {
      if (!std::filesystem::exists(file)) continue;
      try {
        // Every cell is a number, except grid_difference and grid_converged of a grid whose refinement was
        // not checked (grid_coarse_points 0, --grid-tolerance 0): empty there.
        const io::DataTable table = io::ReadCsv(file, {.missing_as_nan = true});
        const auto at = std::find(table.names.begin(), table.names.end(), "grid_coarse_points");
        const Eigen::Index coarse = at == table.names.end() ? -1 : at - table.names.begin();
        for (Eigen::Index r = 0; r < table.values.rows(); ++r)
          for (Eigen::Index c = 0; c < table.values.cols(); ++c) {
            const std::string& name = table.names[static_cast<std::size_t>(c)];
            const bool unchecked =
                coarse >= 0 && table.values(r, coarse) == 0 && (name == "grid_difference" || name == "grid_converged");
            if (!std::isfinite(table.values(r, c)) && !unchecked)
              return "mems output " + file + ": column '" + name + "' of data row " + std::to_string(r + 1) +
                     " is not a number:" + call;
          }
      } catch (const std::exception& e) {
        return "mems output " + file + " does not read back (" + e.what() + "):" + call;
      }
    }
  return "";
}

}  // namespace ident::fuzz
