#pragma once
// A small job system: a fixed set of worker threads that share out loops over indices with the
// thread that asks (JobPool::for_each). It is what runs a frame's independent work in parallel
// (the cameras' detections, matching's seeds and clusters, docs/tracking.md "Threads").
//
// Determinism is the caller's, and easy to keep: for_each(n, fn) calls fn(i) once for every i,
// in no set order and on any thread, so fn writes only what belongs to i (slot i of an output
// array) and the results are the same whatever the thread count. A pool of one thread runs
// everything on the caller, in order.
//
// Why not a library: Debian's oneTBB (libtbb-dev) would do the same, but a frame's loops are a few
// dozen to a few thousand short items, dispatched some tens of times a frame; what they need is
// a dispatch of a few microseconds (workers spin briefly before they sleep) and nothing else.
// This is about 150 lines, with no dependency, and runs as is under the sanitizers (its tests are
// also clean under ThreadSanitizer: clang++-19 -std=c++23 -O1 -g -fsanitize=thread -I. base/Jobs.cpp
// base/Check.cpp tests/base/jobs_test.cpp -lgtest -lgtest_main -lfmt -lspdlog).

#include <atomic>
#include <cstdint>
#include <condition_variable>
#include <cstddef>
#include <exception>
#include <mutex>
#include <thread>
#include <type_traits>
#include <vector>

namespace rhot {

// The threads this process can run at once: the cores it may run on (its CPU affinity, which
// taskset and a container's cpuset limit; elsewhere std::thread::hardware_concurrency), at least 1.
int hardware_threads();

// A thread count from a flag: 0 means every core there is (hardware_threads()).
int threads_or_all(int threads);

// The most threads a flag may ask for.
inline constexpr int kMaxThreads = 256;

class JobPool {
 public:
  // threads: how many threads work on a loop, the caller's included (threads - 1 workers are
  // started). Precondition: threads >= 1. Throws std::system_error when the system starts no
  // more threads (the ones started are stopped first).
  explicit JobPool(int threads);
  ~JobPool();
  JobPool(const JobPool&) = delete;
  JobPool& operator=(const JobPool&) = delete;

  int threads() const { return static_cast<int>(workers_.size()) + 1; }

  // Calls fn(i) once for every i in [0, n), spread over the pool's threads in runs of `grain`
  // indices, and returns when every call has returned. Called from inside one of this pool's
  // loops (a job that itself loops), it runs inline on the calling thread.
  // Exceptions are for failures, not results: when a call throws, the rest of its run of `grain`
  // indices is skipped (on one thread, every index after it), the other runs go on, and one
  // exception is rethrown here once all have returned (the first thrown in time: which one, when
  // several calls throw, depends on the threads).
  template <class F>
  void for_each(std::size_t n, F&& fn, std::size_t grain = 1) {
    auto run_range = [](void* context, std::size_t begin, std::size_t end) {
      F& f = *static_cast<std::remove_reference_t<F>*>(context);
      for (std::size_t i = begin; i < end; ++i) f(i);
    };
    run(n, grain, run_range, const_cast<void*>(static_cast<const void*>(&fn)));
  }

 private:
  using RangeFn = void (*)(void* context, std::size_t begin, std::size_t end);
  void run(std::size_t n, std::size_t grain, RangeFn fn, void* context);
  void take_runs();  // runs of the current job until none are left
  void worker_main();
  void stop_workers();

  std::vector<std::thread> workers_;
  std::mutex run_mutex_;  // one loop at a time, whoever asks
  // The job: written under mutex_ by run() before generation_ moves on. A worker joins it under
  // mutex_ (inside_ + 1) only while indices are left, and run() returns only once inside_ is 0,
  // so no worker reads a job that run() has left or the next one is writing.
  std::mutex mutex_;
  std::condition_variable wake_;  // workers: a new job, or stop
  std::condition_variable done_;  // run(): the last worker left the job
  std::atomic<std::uint64_t> generation_{0};
  bool stop_ = false;
  RangeFn fn_ = nullptr;
  void* context_ = nullptr;
  std::size_t n_ = 0;
  std::size_t grain_ = 1;
  std::atomic<std::size_t> next_{0};  // the first index no thread has taken
  std::atomic<int> inside_{0};        // workers in the job (changed under mutex_)
  std::exception_ptr error_;          // the first exception a call threw
};

}  // namespace rhot
