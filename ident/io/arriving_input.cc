#include "ident/io/arriving_input.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <streambuf>
#include <vector>

#include <fmt/format.h>

#include "common/error.h"
#include "ident/io/csv.h"

namespace ident::io {
namespace {

constexpr std::size_t kArrivingBufferBytes = 1 << 16;

// A read-only stream buffer over a descriptor: each refill is one read(2), short or not.
class DescriptorBuffer final : public std::streambuf {
 public:
  DescriptorBuffer(int fd, bool owned, std::function<void()> before_wait)
      : fd_(fd), owned_(owned), before_wait_(std::move(before_wait)), buffer_(kArrivingBufferBytes) {
    setg(buffer_.data(), buffer_.data(), buffer_.data());
  }
  ~DescriptorBuffer() override {
    if (owned_) ::close(fd_);
  }
  DescriptorBuffer(const DescriptorBuffer&) = delete;
  DescriptorBuffer& operator=(const DescriptorBuffer&) = delete;

 protected:
  int_type underflow() override {
    if (gptr() < egptr()) return traits_type::to_int_type(*gptr());
    const std::size_t got = Read(buffer_.data(), buffer_.size());
    setg(buffer_.data(), buffer_.data(), buffer_.data() + got);
    return got == 0 ? traits_type::eof() : traits_type::to_int_type(*gptr());
  }
  // What is buffered, else one read(2) straight into `s`: never waits for more than the first bytes.
  std::streamsize xsgetn(char* s, std::streamsize n) override {
    if (n <= 0) return 0;
    if (gptr() < egptr()) {
      const std::streamsize k = std::min<std::streamsize>(n, egptr() - gptr());
      std::memcpy(s, gptr(), static_cast<std::size_t>(k));
      gbump(static_cast<int>(k));
      return k;
    }
    return static_cast<std::streamsize>(Read(s, static_cast<std::size_t>(n)));
  }

 private:
  std::size_t Read(char* s, std::size_t n) {
    if (before_wait_) before_wait_();
    while (true) {
      const ssize_t got = ::read(fd_, s, n);
      if (got >= 0) return static_cast<std::size_t>(got);
      if (errno != EINTR) throw std::runtime_error(std::strerror(errno));
    }
  }

  int fd_;
  bool owned_;
  std::function<void()> before_wait_;
  std::vector<char> buffer_;
};

// An istream that owns its buffer.
class ArrivingStream final : public std::istream {
 public:
  explicit ArrivingStream(std::unique_ptr<DescriptorBuffer> buffer)
      : std::istream(buffer.get()), buffer_(std::move(buffer)) {}

 private:
  std::unique_ptr<DescriptorBuffer> buffer_;
};

}  // namespace

std::unique_ptr<std::istream> OpenArrivingInput(const std::string& path, std::function<void()> before_wait) {
  if (path == kStandardInput)
    return std::make_unique<ArrivingStream>(std::make_unique<DescriptorBuffer>(0, false, std::move(before_wait)));
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    throw DataError(fmt::format("cannot read '{}': it is a directory", path));
  int fd = -1;
  do fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  while (fd < 0 && errno == EINTR);
  if (fd < 0) throw DataError(fmt::format("cannot open '{}': {}", path, std::strerror(errno)));
  return std::make_unique<ArrivingStream>(std::make_unique<DescriptorBuffer>(fd, true, std::move(before_wait)));
}

}  // namespace ident::io
