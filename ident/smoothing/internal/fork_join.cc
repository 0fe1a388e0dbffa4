#include "ident/smoothing/internal/fork_join.h"

#include <chrono>

namespace ident::internal {
namespace {

// How long a waiting thread spins before it sleeps: longer than the gaps between a solver's passes (its
// scalar work between them), shorter than a time slice. It yields between rounds of spinning: a partner that
// the scheduler has put on the same CPU then runs instead of waiting for the spinner's time slice to end.
constexpr std::chrono::microseconds kSpin{200};

template <class Done>
bool SpinUntil(Done done) {
  const auto until = std::chrono::steady_clock::now() + kSpin;
  for (;;) {
    for (int i = 0; i < 64; ++i) {
      if (done()) return true;
#if defined(__x86_64__) || defined(__i386__)
      __builtin_ia32_pause();
#endif
    }
    std::this_thread::yield();
    if (std::chrono::steady_clock::now() > until) return false;
  }
}

}  // namespace

ForkJoin::ForkJoin(bool use_worker) {
  if (use_worker && std::thread::hardware_concurrency() >= 2) worker_ = std::thread([this] { Loop(); });
}

ForkJoin::~ForkJoin() {
  if (!parallel()) return;
  {
    const std::lock_guard lock(mutex_);
    stop_.store(true, std::memory_order_release);
  }
  posted_cv_.notify_one();
  worker_.join();
}

unsigned ForkJoin::Post() {
  unsigned generation;
  {
    const std::lock_guard lock(mutex_);
    generation = posted_.fetch_add(1, std::memory_order_release) + 1;
  }
  posted_cv_.notify_one();
  return generation;
}

bool ForkJoin::Claim(unsigned generation) {
  unsigned previous = generation - 1;
  return claimed_.compare_exchange_strong(previous, generation, std::memory_order_acq_rel);
}

void ForkJoin::Wait(unsigned generation) {
  const auto finished = [&] { return done_.load(std::memory_order_acquire) == generation; };
  if (SpinUntil(finished)) return;
  std::unique_lock lock(mutex_);
  done_cv_.wait(lock, finished);
}

void ForkJoin::Loop() {
  unsigned seen = 0;
  for (;;) {
    const auto ready = [&] {
      return posted_.load(std::memory_order_acquire) != seen || stop_.load(std::memory_order_acquire);
    };
    if (!SpinUntil(ready)) {
      std::unique_lock lock(mutex_);
      posted_cv_.wait(lock, ready);
    }
    if (stop_.load(std::memory_order_acquire)) return;
    seen = posted_.load(std::memory_order_acquire);
    if (!Claim(seen)) continue;  // the caller took it (or it is not the newest task: the caller took that one)
    call_(task_);
    {
      const std::lock_guard lock(mutex_);
      done_.store(seen, std::memory_order_release);
    }
    done_cv_.notify_one();
  }
}

}  // namespace ident::internal
