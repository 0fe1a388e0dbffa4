// WorkArena: zeroed, aligned, disjoint arrays within the capacity; huge pages only for large blocks, up to the
// caller's limit; over-use is an InvalidArgument.
#include "ident/linalg/work_arena.h"

#include <cstdint>

#include <gtest/gtest.h>

#include "common/error.h"

namespace ident {
namespace {

void CheckArrays(std::size_t n1, std::size_t n2) {
  WorkArena arena(WorkArena::Padded(n1) + WorkArena::Padded(n2));
  double* a = arena.Take(n1);
  double* b = arena.Take(n2);
  EXPECT_EQ(reinterpret_cast<std::uintptr_t>(a) % 64, 0u);
  EXPECT_EQ(reinterpret_cast<std::uintptr_t>(b) % 64, 0u);
  EXPECT_GE(b, a + n1);  // disjoint
  for (std::size_t i = 0; i < n1; ++i) ASSERT_EQ(a[i], 0.0) << i;
  for (std::size_t i = 0; i < n2; ++i) ASSERT_EQ(b[i], 0.0) << i;
  for (std::size_t i = 0; i < n1; ++i) a[i] = 1.0;  // writable, does not touch b
  for (std::size_t i = 0; i < n2; ++i) ASSERT_EQ(b[i], 0.0) << i;
  EXPECT_EQ(arena.used(), arena.capacity());
  EXPECT_THROW(arena.Take(1), InvalidArgument);
}

TEST(WorkArena, SmallBlocksComeFromTheHeap) {
  CheckArrays(3, 13);
  WorkArena arena(100);
  EXPECT_FALSE(arena.huge_pages_requested());
  EXPECT_EQ(WorkArena::Padded(0), 0u);
  EXPECT_EQ(WorkArena::Padded(1), 8u);
  EXPECT_EQ(WorkArena::Padded(8), 8u);
  EXPECT_EQ(WorkArena::Padded(9), 16u);
}

TEST(WorkArena, LargeBlocksAreZeroedAlignedAndDisjoint) {
  CheckArrays(300001, 170003);  // 3.7 MB: above kHugePageThreshold
#if defined(__linux__)
  WorkArena arena(WorkArena::kHugePageThreshold / sizeof(double));
  EXPECT_TRUE(arena.huge_pages_requested());
#endif
}

TEST(WorkArena, BlocksBeyondTheHugePageLimitAreMappedWithSmallPages) {
  const std::size_t n = 3 * WorkArena::kHugePageThreshold / sizeof(double);
  WorkArena arena(n, /*huge_page_limit=*/2 * WorkArena::kHugePageThreshold);
  EXPECT_FALSE(arena.huge_pages_requested());
  double* a = arena.Take(n);
  EXPECT_EQ(reinterpret_cast<std::uintptr_t>(a) % 64, 0u);
  for (std::size_t i = 0; i < n; ++i) ASSERT_EQ(a[i], 0.0) << i;
#if defined(__linux__)
  WorkArena within(n, /*huge_page_limit=*/n * sizeof(double));
  EXPECT_TRUE(within.huge_pages_requested());
#endif
}

TEST(WorkArena, TakeBeyondTheCapacityNamesTheSizes) {
  WorkArena arena(16);
  arena.Take(10);
  try {
    arena.Take(7);
    FAIL() << "no exception";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("7 doubles requested, 0 of 16 left"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace ident
