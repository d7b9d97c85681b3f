#include "base/Jobs.h"

#include <algorithm>
#include <utility>

#include "base/Check.h"

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#endif
#if defined(__linux__)
#include <sched.h>
#endif

namespace rhot {

namespace {

// The pool whose loop this thread is running now (a job that loops again runs inline).
thread_local const JobPool* t_running_for = nullptr;

// A loop's items take microseconds, and a frame dispatches some tens of loops: a worker that has
// just finished one spins this many pauses (tens of microseconds) for the next before it sleeps,
// and the caller as many for the workers' last runs, so back-to-back loops cost no wake-up.
constexpr int kSpins = 4000;

void pause() {
#if defined(__x86_64__) || defined(__i386__)
  _mm_pause();
#elif defined(__aarch64__)
  asm volatile("yield");
#endif
}

}  // namespace

int hardware_threads() {
#if defined(__linux__)
  // The cores this process may run on (taskset, a container's cpuset), not every core of the host.
  cpu_set_t allowed;
  CPU_ZERO(&allowed);
  if (sched_getaffinity(0, sizeof(allowed), &allowed) == 0) return std::max(1, CPU_COUNT(&allowed));
#endif
  return std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
}

int threads_or_all(int threads) { return threads > 0 ? threads : hardware_threads(); }

JobPool::JobPool(int threads) {
  RHOT_PRECONDITION(threads >= 1, "JobPool: at least one thread");
  workers_.reserve(static_cast<std::size_t>(threads - 1));
  try {
    for (int t = 1; t < threads; ++t) workers_.emplace_back([this] { worker_main(); });
  } catch (...) {
    stop_workers();  // the ones started; then the caller hears why (std::system_error)
    throw;
  }
}

JobPool::~JobPool() { stop_workers(); }

void JobPool::stop_workers() {
  {
    std::lock_guard lock(mutex_);
    stop_ = true;
    generation_.fetch_add(1, std::memory_order_release);
  }
  wake_.notify_all();
  for (std::thread& t : workers_) t.join();
  workers_.clear();
}

void JobPool::take_runs() {
  for (;;) {
    const std::size_t begin = next_.fetch_add(grain_, std::memory_order_relaxed);
    if (begin >= n_) return;
    const std::size_t end = std::min(n_, begin + grain_);
    try {
      fn_(context_, begin, end);
    } catch (...) {
      std::lock_guard lock(mutex_);
      if (!error_) error_ = std::current_exception();
    }
  }
}

void JobPool::worker_main() {
  t_running_for = this;
  std::uint64_t seen = 0;
  for (;;) {
    for (int s = 0; s < kSpins && generation_.load(std::memory_order_acquire) == seen; ++s) pause();
    {
      std::unique_lock lock(mutex_);
      wake_.wait(lock, [&] { return generation_.load(std::memory_order_relaxed) != seen; });
      if (stop_) return;
      seen = generation_.load(std::memory_order_relaxed);
      if (next_.load(std::memory_order_relaxed) >= n_) continue;  // the caller took it all
      inside_.fetch_add(1, std::memory_order_relaxed);
    }
    take_runs();
    {
      std::lock_guard lock(mutex_);
      if (inside_.fetch_sub(1, std::memory_order_acq_rel) == 1) done_.notify_one();
    }
  }
}

void JobPool::run(std::size_t n, std::size_t grain, RangeFn fn, void* context) {
  grain = std::max<std::size_t>(grain, 1);
  if (n == 0) return;
  if (workers_.empty() || n <= grain || t_running_for == this) {
    fn(context, 0, n);
    return;
  }
  std::lock_guard one_loop(run_mutex_);
  {
    std::lock_guard lock(mutex_);
    fn_ = fn;
    context_ = context;
    n_ = n;
    grain_ = grain;
    next_.store(0, std::memory_order_relaxed);
    error_ = nullptr;
    generation_.fetch_add(1, std::memory_order_release);
  }
  wake_.notify_all();
  const JobPool* const was_running_for = std::exchange(t_running_for, this);
  take_runs();
  t_running_for = was_running_for;
  for (int s = 0; s < kSpins && inside_.load(std::memory_order_acquire) != 0; ++s) pause();
  std::exception_ptr error;
  {
    std::unique_lock lock(mutex_);
    done_.wait(lock, [&] { return inside_.load(std::memory_order_relaxed) == 0; });
    error = std::exchange(error_, nullptr);
  }
  if (error) std::rethrow_exception(error);
}

}  // namespace rhot
