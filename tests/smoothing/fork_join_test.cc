// ident/smoothing/internal/fork_join.h: both tasks run, in order without a worker, and every Run returns only after
// both have finished, over many rounds (a lost wake-up or a task claimed twice or never would hang or put a
// round's counts off).
#include "ident/smoothing/internal/fork_join.h"

#include <chrono>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

namespace ident::internal {
namespace {

// An exception from either task reaches the caller, after both tasks have run to their end; with no ForkJoin the
// tasks run in order on the calling thread.
TEST(ForkJoin, RunRethrowingRethrowsOnTheCallerAfterBothTasks) {
  ForkJoin fork(/*use_worker=*/true);
  const auto busy = [] {
    const auto until = std::chrono::steady_clock::now() + std::chrono::microseconds(200);
    while (std::chrono::steady_clock::now() < until) {}
  };
  for (int thrower = 0; thrower < 3; ++thrower)
    for (ForkJoin* f : {&fork, static_cast<ForkJoin*>(nullptr)}) {
      bool a_done = false, b_done = false;
      std::string caught;
      try {
        RunRethrowing(
            f,
            [&] {
              busy();
              a_done = true;
              if (thrower != 1) throw std::runtime_error("a");
            },
            [&] {
              busy();
              b_done = true;
              if (thrower != 0) throw std::runtime_error("b");
            });
      } catch (const std::runtime_error& e) {
        caught = e.what();
      }
      EXPECT_TRUE(a_done && b_done) << thrower;
      EXPECT_EQ(caught, thrower == 1 ? "b" : "a") << thrower;  // thrower 2: both throw, a()'s wins
    }
  std::vector<int> order;
  RunRethrowing(
      nullptr, [&] { order.push_back(1); }, [&] { order.push_back(2); });
  EXPECT_EQ(order, (std::vector<int>{1, 2}));
}

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

// Whichever thread claims the second task runs it: with a trivial first task the caller mostly takes both
// (the worker is still waking up), with a longer one the spinning worker takes the second.
TEST(ForkJoin, EveryRoundReturnsWithBothTasksDone) {
  ForkJoin fork(/*use_worker=*/true);
  if (std::thread::hardware_concurrency() >= 2) {
    EXPECT_TRUE(fork.parallel());
  }
  long a = 0, b = 0;  // plain: Run's return orders the worker's writes before the caller's reads
  const auto busy = [](std::chrono::microseconds d) {
    const auto until = std::chrono::steady_clock::now() + d;
    while (std::chrono::steady_clock::now() < until) {}
  };
  for (int round = 1; round <= 20000; ++round) {
    const bool slow = round > 18000;  // the last rounds' first task takes 50 us
    fork.Run(
        [&] {
          ++a;
          if (slow) busy(std::chrono::microseconds(50));
        },
        [&] { ++b; });
    ASSERT_EQ(a, round);
    ASSERT_EQ(b, round);
    if (round % 5000 == 0) std::this_thread::sleep_for(std::chrono::milliseconds(2));  // the worker sleeps
  }
}

TEST(ForkJoin, ASpinningWorkerTakesTheSecondTask) {
  ForkJoin fork(/*use_worker=*/true);
  if (!fork.parallel()) GTEST_SKIP() << "one hardware thread";
  const std::thread::id caller = std::this_thread::get_id();
  int on_worker = 0;
  for (int round = 0; round < 200; ++round) {
    std::thread::id b_thread;
    fork.Run(
        [] {
          const auto until = std::chrono::steady_clock::now() + std::chrono::microseconds(200);
          while (std::chrono::steady_clock::now() < until) {}
        },
        [&] { b_thread = std::this_thread::get_id(); });
    on_worker += b_thread != caller;
  }
  EXPECT_GT(on_worker, 0);
}

}  // namespace
}  // namespace ident::internal
