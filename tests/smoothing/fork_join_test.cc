// ident/smoothing/internal/fork_join.h: both tasks run, in order without a worker, and every Run returns only after
// both have finished, over many rounds (a lost wake-up would hang or let a round's counts fall behind).
#include "ident/smoothing/internal/fork_join.h"

#include <chrono>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

namespace ident::internal {
namespace {

TEST(ForkJoin, WithoutAWorkerRunsTheTasksInOrderOnTheCallingThread) {
  ForkJoin fork(/*use_worker=*/false);
  EXPECT_FALSE(fork.parallel());
  std::vector<int> order;
  std::thread::id a_thread, b_thread;
  fork.Run([&] { order.push_back(1), a_thread = std::this_thread::get_id(); },
           [&] { order.push_back(2), b_thread = std::this_thread::get_id(); });
  EXPECT_EQ(order, (std::vector<int>{1, 2}));
  EXPECT_EQ(a_thread, std::this_thread::get_id());
  EXPECT_EQ(b_thread, std::this_thread::get_id());
}

TEST(ForkJoin, EveryRoundReturnsWithBothTasksDone) {
  ForkJoin fork(/*use_worker=*/true);
  if (std::thread::hardware_concurrency() >= 2) {
    EXPECT_TRUE(fork.parallel());
  }
  long a = 0, b = 0;  // plain: Run's return orders the worker's writes before the caller's reads
  std::thread::id b_thread;
  for (int round = 1; round <= 20000; ++round) {
    fork.Run([&] { ++a; }, [&] { ++b, b_thread = std::this_thread::get_id(); });
    ASSERT_EQ(a, round);
    ASSERT_EQ(b, round);
    if (round % 5000 == 0) std::this_thread::sleep_for(std::chrono::milliseconds(2));  // the worker sleeps
  }
  if (fork.parallel()) {
    EXPECT_NE(b_thread, std::this_thread::get_id());
  }
}

}  // namespace
}  // namespace ident::internal
