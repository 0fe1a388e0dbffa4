// An output file that appears complete or not at all.
//
// OutputFile writes to a temporary file created next to the target (same directory, so the final
// rename(2) is atomic) and renames it onto the target only in Commit(), after every byte has been
// flushed, synced and the file closed without error. Until then the target keeps its old content (or
// stays absent); a destroyed, uncommitted OutputFile (an exception, an early return) removes its
// temporary file. A symbolic link as target is followed: the temporary file goes next to the file the
// link resolves to and is renamed onto that file, so the link itself stays a link.
//
// On SIGTERM, SIGINT, SIGHUP or SIGPIPE an async-signal-safe handler unlinks every temporary file still open
// (a fixed table of paths), restores the signal's previous action and raises it again; the targets
// are untouched. The handler is installed when the first OutputFile is created.
//
//   OutputFile out("trace.csv", "--trace file");   // throws InvalidArgument naming the file
//   fmt::print(out.stream(), "t,y\n");
//   ...
//   out.Commit();                                    // throws InvalidArgument on a write error
//
// A new file gets mode 0666 & ~umask, a replaced one keeps its mode; an existing file the process may
// not write (access(2) W_OK) is refused, as opening it for writing would be. The rename gives the target
// a new inode: other hard links to the old file keep the old content. Which targets a command refuses
// (an input file, two equal outputs, a device or fifo) is decided by cli/output_paths.h, which the
// commands call before any work; the constructor also refuses an existing target that is not a regular
// file.
#pragma once

#include <cstdio>
#include <string>
#include <string_view>

namespace ident::cli {

class OutputFile {
 public:
  // `what` names the file in messages, e.g. "--trace file": "cannot write --trace file 'x': <reason>".
  OutputFile(std::string path, std::string what);
  ~OutputFile();  // removes the temporary file unless committed
  OutputFile(const OutputFile&) = delete;
  OutputFile& operator=(const OutputFile&) = delete;

  // The stream of the temporary file (nullptr after Close()). Writes are checked by Close().
  std::FILE* stream() const { return file_; }
  // Appends `text`; throws InvalidArgument if the write fails.
  void Write(std::string_view text);

  // Flushes, syncs and closes the temporary file; throws InvalidArgument naming the target on any
  // error (the temporary file is removed then). Idempotent. For several outputs, Close() them all
  // before the first Commit(), so a write error leaves every target untouched.
  void Close();
  // Close(), then renames the temporary file onto the target. Throws InvalidArgument on failure.
  void Commit();

  const std::string& path() const { return path_; }            // the target as given
  const std::string& temp_path() const { return temp_path_; }  // for a program that writes the file itself
  bool committed() const { return committed_; }

 private:
  [[noreturn]] void Fail(const std::string& reason);
  void Discard() noexcept;

  std::string path_, what_;
  std::string final_path_;  // the target after following symbolic links
  std::string temp_path_;
  std::FILE* file_ = nullptr;
  int slot_ = -1;           // index in the signal handler's table
  bool owns_temp_ = false;  // the temporary file exists and is this object's to rename or remove
  bool committed_ = false;
};

// Number of temporary files the signal handler currently knows of (for tests).
int PendingOutputFiles();

}  // namespace ident::cli
