// Counts heap allocations in this thread: operator new and malloc-family calls, so Eigen's dynamic
// matrices (which call std::malloc) are counted too (test helper; see alloc_counter.cc).
//
// Example:
//   ident::testing::AllocationCounter count;
//   for (...) est.Update(y, z);
//   EXPECT_EQ(count.allocations(), 0);
#pragma once

#include <cstddef>
#include <cstdint>

namespace ident::testing {

std::int64_t AllocationsSoFar();  // total operator-new calls in this thread since start
// Allocations of at least kLargeAllocationBytes: blocks an allocator may take from and hand back to the
// system each time (glibc does above its trim threshold, which Dask workers lower to this size).
inline constexpr std::size_t kLargeAllocationBytes = 64 * 1024;
std::int64_t LargeAllocationsSoFar();

class AllocationCounter {
 public:
  AllocationCounter() : start_(AllocationsSoFar()) {}
  std::int64_t allocations() const { return AllocationsSoFar() - start_; }
  std::int64_t large_allocations() const { return LargeAllocationsSoFar() - large_start_; }

 private:
  std::int64_t start_;
  std::int64_t large_start_ = LargeAllocationsSoFar();
};

}  // namespace ident::testing
