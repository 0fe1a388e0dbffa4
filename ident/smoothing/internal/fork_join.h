// Two tasks at once: one on the calling thread, the other on a worker thread that lives as long as the
// ForkJoin (internal to ident/smoothing/; the MAP smoother's fast path splits each pass over the time steps into
// a top half and a bottom half). Between tasks the worker spins for a short while, then sleeps; the caller waits
// the same way. The second task goes to whichever thread claims it first: a caller done with its own task
// before the worker has woken up runs it itself (a sleeping or descheduled worker can take milliseconds to
// wake). Without a worker the tasks run one after the other on the calling thread; a solver that splits its
// work the same way either way gives the same numbers on one thread or two.
//
// Example:
//   ForkJoin fork(/*use_worker=*/true);
//   fork.Run([&] { Top(); }, [&] { Bottom(); });   // both done on return
//   RunRethrowing(&fork, [&] { MayThrow(); }, [&] { Other(); });
#pragma once

#include <atomic>
#include <condition_variable>
#include <exception>
#include <mutex>
#include <thread>
#include <type_traits>

namespace ident::internal {

class ForkJoin {
 public:
  explicit ForkJoin(bool use_worker);
  ~ForkJoin();
  ForkJoin(const ForkJoin&) = delete;
  ForkJoin& operator=(const ForkJoin&) = delete;

  bool parallel() const { return worker_.joinable(); }

  // Runs a() here and b() on the worker or here (or a() then b()); returns when both have returned. Neither may
  // throw; one thread calls Run at a time.
  template <class A, class B>
  void Run(A&& a, B&& b) {
    if (!parallel()) {
      a();
      b();
      return;
    }
    task_ = &b;
    call_ = [](void* f) { (*static_cast<std::remove_reference_t<B>*>(f))(); };
    const unsigned generation = Post();
    a();
    if (Claim(generation))
      b();
    else
      Wait(generation);
  }

 private:
  unsigned Post();                  // the new task's generation
  bool Claim(unsigned generation);  // true for the one thread that takes that task
  void Wait(unsigned generation);   // until the worker has finished the task it claimed
  void Loop();

  std::mutex mutex_;
  std::condition_variable posted_cv_, done_cv_;
  std::atomic<unsigned> posted_{0}, claimed_{0}, done_{0};  // generations: posted >= claimed >= done
  std::atomic<bool> stop_{false};
  void* task_ = nullptr;
  void (*call_)(void*) = nullptr;
  std::thread worker_;  // last: started once the members above exist
};

// a() and b() by fork->Run (one after the other if `fork` is null), for tasks that may throw: both run to their
// end either way, and an exception from either is caught where it is thrown and rethrown here (a()'s if both
// throw).
template <class A, class B>
void RunRethrowing(ForkJoin* fork, A&& a, B&& b) {
  std::exception_ptr error_a, error_b;
  auto caught_a = [&] {
    try {
      a();
    } catch (...) {
      error_a = std::current_exception();
    }
  };
  auto caught_b = [&] {
    try {
      b();
    } catch (...) {
      error_b = std::current_exception();
    }
  };
  if (fork != nullptr) {
    fork->Run(caught_a, caught_b);
  } else {
    caught_a();
    caught_b();
  }
  if (error_a) std::rethrow_exception(error_a);
  if (error_b) std::rethrow_exception(error_b);
}

}  // namespace ident::internal
