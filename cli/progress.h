// Progress of a long command on stderr: nothing during its first 2 s (a short run prints nothing), then
// one line per 10 % of the work — rewritten in place on a terminal, one line each in a log or a pipe.
//
//   Progress progress("fit");
//   progress.Report(done, total, "rows", 2);   // "ident fit: pass 2: 40 % (400 of 1000 rows)"
//   csv.on_read = ReadingProgress(progress, path);   // the same while a file is read
#pragma once

#include <chrono>
#include <functional>
#include <string>

namespace ident::cli {

class Progress {
 public:
  explicit Progress(std::string command);
  ~Progress();
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;

  // `done` of `total` units (`unit` names them) of pass `pass` (0: the work has no passes); a new pass or
  // unit starts its tenths afresh. Cheap when nothing is printed (called once per row of a fit).
  void Report(long done, long total, const char* unit, int pass = 0);

 private:
  std::string command_;
  std::chrono::steady_clock::time_point start_;
  bool terminal_;
  int pass_ = 0;
  std::string unit_;
  const char* unit_pointer_ = nullptr;  // the `unit` last passed: a literal repeats it, and is not compared
  int reported_ = 0;                    // tenths of the current stage reported
  bool open_line_ = false;              // a terminal line without its newline yet
};

// io::CsvOptions::on_read for a file being read whole: "ident predict: 40 % (120 of 300 MB read)". Empty
// for standard input, a .mat file and anything whose size is unknown.
std::function<void(long)> ReadingProgress(Progress& progress, const std::string& path);

// For an iterative method whose number of iterations is not known in advance but whose convergence measure
// falls from the first iteration's value to `tolerance` about geometrically: the decades it has fallen of
// those it must fall are the work done. Call with (iteration, measure), iteration 0 first.
std::function<void(int, double)> DecadesProgress(Progress& progress, double tolerance, const char* unit);

}  // namespace ident::cli
