#include "ident/linalg/work_arena.h"

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <new>

#if defined(__linux__)
#include <sys/mman.h>
#endif

#include "common/error.h"

namespace ident {
namespace {
constexpr std::size_t kHugePage = std::size_t{2} << 20;
constexpr std::size_t kAlign = 64;
}  // namespace

WorkArena::WorkArena(std::size_t num_doubles, std::size_t huge_page_limit) : capacity_(Padded(num_doubles)) {
  const std::size_t bytes = std::max<std::size_t>(capacity_, 8) * sizeof(double);
#if defined(__linux__)
  if (bytes >= kHugePageThreshold) {
    // Over-map by one huge page so that the block can start on a 2 MiB boundary.
    const std::size_t length = (bytes + kHugePage - 1) / kHugePage * kHugePage + kHugePage;
    void* p = mmap(nullptr, length, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (p != MAP_FAILED) {
      mapping_ = p;
      mapped_bytes_ = length;
      const auto start = (reinterpret_cast<std::uintptr_t>(p) + kHugePage - 1) & ~(kHugePage - 1);
      data_ = reinterpret_cast<double*>(start);
      huge_pages_ = bytes <= huge_page_limit;
      if (huge_pages_) madvise(data_, length - kHugePage, MADV_HUGEPAGE);  // advice only: ignored where unsupported
      return;                                                              // anonymous mappings are zero-filled
    }
  }
#endif
  const std::size_t rounded = (bytes + kAlign - 1) / kAlign * kAlign;
  data_ = static_cast<double*>(std::aligned_alloc(kAlign, rounded));
  if (data_ == nullptr) throw std::bad_alloc();
  std::memset(data_, 0, rounded);
}

WorkArena::~WorkArena() {
#if defined(__linux__)
  if (mapping_ != nullptr) {
    munmap(mapping_, mapped_bytes_);
    return;
  }
#endif
  std::free(data_);
}

double* WorkArena::Take(std::size_t count) {
  const std::size_t padded = Padded(count);
  IDENT_REQUIRE(used_ + padded <= capacity_, "WorkArena: {} doubles requested, {} of {} left", count, capacity_ - used_,
                capacity_);
  double* p = data_ + used_;
  used_ += padded;
  return p;
}

}  // namespace ident
