#include "cli/output_file.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <csignal>
#include <cstring>
#include <mutex>

#include <fmt/format.h>

#include "common/error.h"

namespace ident::cli {
namespace {

// The signal handler's table of temporary files: a slot is written while every handled signal is
// blocked, and `used` is set last, so the handler only ever sees complete paths.
constexpr int kSlots = 32;
constexpr std::size_t kMaxPath = 4096;
struct Slot {
  volatile std::sig_atomic_t used = 0;
  char path[kMaxPath] = {};
};
std::array<Slot, kSlots> g_slots;

constexpr std::array<int, 4> kSignals = {SIGTERM, SIGINT, SIGHUP, SIGPIPE};
std::array<struct sigaction, kSignals.size()> g_previous;

extern "C" void RemoveTemporaryFilesAndReraise(int signal_number) {
  const int saved_errno = errno;
  for (Slot& slot : g_slots)
    if (slot.used) unlink(slot.path);
  for (std::size_t i = 0; i < kSignals.size(); ++i)
    if (kSignals[i] == signal_number) sigaction(signal_number, &g_previous[i], nullptr);
  raise(signal_number);  // delivered with the previous action once this handler returns
  errno = saved_errno;
}

void InstallHandlerOnce() {
  static std::once_flag once;
  std::call_once(once, [] {
    for (std::size_t i = 0; i < kSignals.size(); ++i) {
      struct sigaction previous {};
      sigaction(kSignals[i], nullptr, &previous);
      g_previous[i] = previous;
      if (previous.sa_handler == SIG_IGN) continue;  // e.g. SIGHUP under nohup: stays ignored
      struct sigaction action {};
      action.sa_handler = &RemoveTemporaryFilesAndReraise;
      sigemptyset(&action.sa_mask);
      for (int s : kSignals) sigaddset(&action.sa_mask, s);
      sigaction(kSignals[i], &action, nullptr);
    }
  });
}

// Blocks the handled signals for its lifetime, so a slot and its file appear and vanish together.
class SignalBlock {
 public:
  SignalBlock() {
    sigset_t set;
    sigemptyset(&set);
    for (int s : kSignals) sigaddset(&set, s);
    sigprocmask(SIG_BLOCK, &set, &saved_);
  }
  ~SignalBlock() { sigprocmask(SIG_SETMASK, &saved_, nullptr); }
  SignalBlock(const SignalBlock&) = delete;
  SignalBlock& operator=(const SignalBlock&) = delete;

 private:
  sigset_t saved_;
};

int ClaimSlot(const std::string& path) {
  for (int i = 0; i < kSlots; ++i) {
    Slot& slot = g_slots[static_cast<std::size_t>(i)];
    if (slot.used) continue;
    std::memcpy(slot.path, path.c_str(), path.size() + 1);
    slot.used = 1;
    return i;
  }
  return -1;
}

void ReleaseSlot(int i) {
  if (i >= 0) g_slots[static_cast<std::size_t>(i)].used = 0;
}

// Follows symbolic links (relative ones against the link's directory) to the file they name, which
// need not exist.
std::string ResolveLinks(const std::string& path, std::string& problem) {
  std::string current = path;
  for (int hops = 0; hops < 40; ++hops) {
    struct stat st {};
    if (lstat(current.c_str(), &st) != 0 || !S_ISLNK(st.st_mode)) return current;
    std::string target(kMaxPath, '\0');
    const ssize_t n = readlink(current.c_str(), target.data(), target.size());
    if (n < 0 || static_cast<std::size_t>(n) >= target.size()) {
      problem = "cannot read the symbolic link";
      return current;
    }
    target.resize(static_cast<std::size_t>(n));
    if (target.front() != '/') {
      const std::size_t slash = current.rfind('/');
      if (slash != std::string::npos) target = current.substr(0, slash + 1) + target;
    }
    current = target;
  }
  problem = "too many levels of symbolic links";
  return current;
}

}  // namespace

int PendingOutputFiles() {
  int n = 0;
  for (const Slot& slot : g_slots) n += slot.used ? 1 : 0;
  return n;
}

OutputFile::OutputFile(std::string path, std::string what) : path_(std::move(path)), what_(std::move(what)) {
  if (path_.empty()) Fail("empty file name");
  std::string problem;
  final_path_ = ResolveLinks(path_, problem);
  if (!problem.empty()) Fail(problem);
  mode_t mode = 0;
  struct stat st {};
  if (stat(final_path_.c_str(), &st) == 0) {
    if (!S_ISREG(st.st_mode)) Fail("not a regular file (a device, fifo or directory)");
    if (access(final_path_.c_str(), W_OK) != 0) Fail(std::strerror(errno));  // a read-only file stays so
    mode = st.st_mode & 07777;
  } else {
    const mode_t mask = umask(0);
    umask(mask);
    mode = 0666 & ~mask;
  }
  const std::size_t slash = final_path_.rfind('/');
  const std::string dir = slash == std::string::npos ? "" : final_path_.substr(0, slash + 1);
  const std::string base = slash == std::string::npos ? final_path_ : final_path_.substr(slash + 1);
  if (base.empty() || base == "." || base == "..") Fail("not a file name");
  std::string pattern = dir + "." + base + ".tmp-XXXXXX";
  if (pattern.size() >= kMaxPath) Fail("file name too long");
  InstallHandlerOnce();
  {
    SignalBlock block;
    const int fd = mkostemp(pattern.data(), O_CLOEXEC);
    if (fd < 0) Fail(std::strerror(errno));
    temp_path_ = pattern;
    owns_temp_ = true;
    slot_ = ClaimSlot(temp_path_);
    file_ = fdopen(fd, "w");
    if (!file_) {
      const int error = errno;
      close(fd);
      Fail(std::strerror(error));
    }
  }
  if (slot_ < 0) Fail("too many output files at once");
  if (fchmod(fileno(file_), mode) != 0) Fail(std::strerror(errno));
}

OutputFile::~OutputFile() {
  if (!committed_) Discard();
}

void OutputFile::Write(std::string_view text) {
  if (!file_) Fail("write after close");
  if (std::fwrite(text.data(), 1, text.size(), file_) != text.size()) Fail(std::strerror(errno));
}

void OutputFile::Close() {
  if (!file_) {
    if (!owns_temp_) Fail("the file was discarded");
    return;  // closed already
  }
  std::FILE* file = file_;
  file_ = nullptr;
  errno = 0;
  int error = 0;
  if (std::fflush(file) != 0 || std::ferror(file)) error = errno ? errno : EIO;
  if (!error && fsync(fileno(file)) != 0) error = errno;
  if (std::fclose(file) != 0 && !error) error = errno;
  if (error) Fail(std::strerror(error));
}

void OutputFile::Commit() {
  if (committed_) return;
  Close();
  if (std::rename(temp_path_.c_str(), final_path_.c_str()) != 0) Fail(std::strerror(errno));
  SignalBlock block;
  ReleaseSlot(slot_);
  slot_ = -1;
  owns_temp_ = false;
  committed_ = true;
}

void OutputFile::Fail(const std::string& reason) {
  Discard();
  throw InvalidArgument(fmt::format("cannot write {} '{}': {}", what_, path_, reason));
}

void OutputFile::Discard() noexcept {
  if (file_) {
    std::fclose(file_);
    file_ = nullptr;
  }
  SignalBlock block;
  if (owns_temp_) unlink(temp_path_.c_str());
  owns_temp_ = false;
  ReleaseSlot(slot_);
  slot_ = -1;
}

}  // namespace ident::cli
