// The allocation counter behind every "allocates nothing" test (tests/support/alloc_counter.h) counts
// what it must, in this build whichever it is (malloc interposition, or ASan's malloc hook): without this
// positive control a counter that silently stopped counting would let all of those tests pass.
#include <cstdlib>
#include <memory>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Core>

#include "tests/support/alloc_counter.h"

namespace ident::testing {
namespace {

// Each allocation's address is stored here, so that the compiler cannot elide the allocation.
void* volatile g_escape = nullptr;

TEST(AllocationCounter, CountsEigenStdVectorOperatorNewAndMalloc) {
  AllocationCounter count;
  {
    Eigen::VectorXd v(64);  // Eigen's aligned malloc
    g_escape = v.data();
  }
  const auto after_eigen = count.allocations();
  EXPECT_GE(after_eigen, 1);
  {
    std::vector<double> w(64, 1.0);  // operator new
    g_escape = w.data();
  }
  const auto after_vector = count.allocations();
  EXPECT_GE(after_vector, after_eigen + 1);
  auto p = std::make_unique<int>(3);
  g_escape = p.get();
  EXPECT_GE(count.allocations(), after_vector + 1);
  void* raw = std::malloc(128);
  ASSERT_NE(raw, nullptr);
  g_escape = raw;
  EXPECT_GE(count.allocations(), after_vector + 2);
  std::free(raw);
}

TEST(AllocationCounter, CountsNothingWhenNothingIsAllocated) {
  Eigen::VectorXd v = Eigen::VectorXd::Ones(64);
  AllocationCounter count;
  for (int i = 0; i < 1000; ++i) v *= 1.0;
  EXPECT_EQ(count.allocations(), 0);
  EXPECT_EQ(v.sum(), 64.0);
}

}  // namespace
}  // namespace ident::testing
