// Shared by the fuzz targets and by tests/cli/fuzz_corpus_test.cc (which replays every
// committed corpus input through the same property checks in the ordinary test suite):
//   ByteReader             reads typed values from the fuzzer's bytes
//   IDENT_FUZZ_ENTRY(fn)   defines LLVMFuzzerTestOneInput from a property check
//                          `std::string fn(const uint8_t*, size_t)` ("" = all properties hold);
//                          a violated property prints its name and traps, so libFuzzer saves the input.
//   ScratchDir             a directory for one process's files, removed when the process exits normally
//                          (a violated property traps, so the files of the failing input stay)
#pragma once

#include <stdlib.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <string>
#include <system_error>

namespace ident::fuzz {

// Consumes the input front to back; reads past the end return zeros.
class ByteReader {
 public:
  ByteReader(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {}
  std::size_t remaining() const { return size_ - pos_; }
  std::uint8_t Byte() { return pos_ < size_ ? data_[pos_++] : 0; }
  // Any bit pattern: NaN, ±Inf, subnormals, ±1e308 all occur.
  double Double() {
    std::uint64_t bits = 0;
    for (int i = 0; i < 8; ++i) bits |= std::uint64_t{Byte()} << (8 * i);
    double v;
    std::memcpy(&v, &bits, sizeof v);
    return v;
  }

 private:
  const std::uint8_t* data_;
  std::size_t size_;
  std::size_t pos_ = 0;
};

// <temporary directory>/<prefix>XXXXXX for one process's files (the temporary directory itself if it
// cannot be made), removed with its contents when the object is destroyed: keep it in a function-local
// static. The test programs' files go into one too (tests/support/cli.h TempDir).
class ScratchDir {
 public:
  explicit ScratchDir(const char* prefix) {
    std::error_code ec;
    const std::filesystem::path base = std::filesystem::temp_directory_path(ec);
    const std::filesystem::path tmp = ec ? std::filesystem::path("/tmp") : base;
    path_ = (tmp / (std::string(prefix) + "XXXXXX")).string();
    made_ = mkdtemp(path_.data()) != nullptr;
    if (!made_) path_ = tmp.string();
  }
  ~ScratchDir() {
    std::error_code ignored;
    if (made_) std::filesystem::remove_all(path_, ignored);
  }
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  bool made_ = false;
};

}  // namespace ident::fuzz

#define IDENT_FUZZ_ENTRY(check)                                                       \
  extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) { \
    const std::string violated = check(data, size);                                   \
    if (!violated.empty()) {                                                          \
      std::fprintf(stderr, "fuzz property violated: %s\n", violated.c_str());         \
      __builtin_trap();                                                               \
    }                                                                                 \
    return 0;                                                                         \
  }
