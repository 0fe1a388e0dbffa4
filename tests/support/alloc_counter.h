// Counts heap allocations in this thread: operator new and malloc-family calls, so Eigen's dynamic
// matrices (which call std::malloc) are counted too (test helper; see alloc_counter.cc).
//
// Example:
//   ident::testing::AllocationCounter count;
//   for (...) est.Update(y, z);
//   EXPECT_EQ(count.allocations(), 0);
#pragma once

#include <cstdint>

namespace ident::testing {

std::int64_t AllocationsSoFar();  // total operator-new calls in this thread since start

class AllocationCounter {
 public:
  AllocationCounter() : start_(AllocationsSoFar()) {}
  std::int64_t allocations() const { return AllocationsSoFar() - start_; }

 private:
  std::int64_t start_;
};

}  // namespace ident::testing
