#include "base/Jobs.h"

#include <atomic>
#include <numeric>
#include <stdexcept>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

namespace rhot {
namespace {

TEST(JobPool, CallsEveryIndexExactlyOnceWhateverTheThreadsAndGrain) {
  for (const int threads : {1, 2, 3, 8}) {
    JobPool pool(threads);
    EXPECT_EQ(pool.threads(), threads);
    for (const std::size_t grain : {std::size_t{1}, std::size_t{7}, std::size_t{1000}}) {
      for (const std::size_t n : {std::size_t{0}, std::size_t{1}, std::size_t{5}, std::size_t{999}, std::size_t{20000}}) {
        std::vector<std::atomic<int>> calls(n);
        pool.for_each(
            n, [&](std::size_t i) { calls[i].fetch_add(1); }, grain);
        for (std::size_t i = 0; i < n; ++i)
          ASSERT_EQ(calls[i].load(), 1) << threads << " threads, grain " << grain << ", n " << n << ", i " << i;
      }
    }
  }
}

TEST(JobPool, SpreadsALoopOverItsThreads) {
  JobPool pool(4);
  // Each call waits for the others to start, so a loop run by fewer than four threads never ends:
  // the pool's workers take part (the test's timeout is the failure).
  std::atomic<int> started{0};
  std::vector<std::thread::id> who(4);
  pool.for_each(4, [&](std::size_t i) {
    started.fetch_add(1);
    while (started.load() < 4) std::this_thread::yield();
    who[i] = std::this_thread::get_id();
  });
  for (std::size_t a = 0; a < 4; ++a) {
    for (std::size_t b = a + 1; b < 4; ++b) EXPECT_NE(who[a], who[b]);
  }
}

TEST(JobPool, ManyLoopsInARowGiveTheSerialResult) {
  JobPool pool(3);
  std::vector<double> out(4096);
  for (int round = 0; round < 2000; ++round) {
    pool.for_each(
        out.size(), [&](std::size_t i) { out[i] = static_cast<double>(i * static_cast<std::size_t>(round)); }, 64);
    ASSERT_EQ(out[4095], 4095.0 * round);
    ASSERT_EQ(out[17], 17.0 * round);
  }
}

TEST(JobPool, AJobThatLoopsAgainRunsItsLoopInline) {
  JobPool pool(2);
  std::vector<std::atomic<int>> calls(64 * 64);
  pool.for_each(64, [&](std::size_t i) { pool.for_each(64, [&](std::size_t j) { calls[i * 64 + j].fetch_add(1); }); });
  for (const auto& c : calls) ASSERT_EQ(c.load(), 1);
}

// A worker of one pool that loops on another pool, then on its own again: the second loop on its
// own pool runs inline, as any nested loop does (it once forgot which pool it was running for, and
// waited for the pool it was part of).
TEST(JobPool, ALoopOnAnotherPoolDoesNotMakeANestedLoopWait) {
  JobPool outer(3);
  JobPool other(2);
  std::vector<std::atomic<int>> calls(8 * 8 * 2);
  outer.for_each(8, [&](std::size_t i) {
    other.for_each(8, [&](std::size_t j) { calls[(i * 8 + j) * 2].fetch_add(1); });
    outer.for_each(8, [&](std::size_t j) { calls[(i * 8 + j) * 2 + 1].fetch_add(1); });
  });
  for (const auto& c : calls) ASSERT_EQ(c.load(), 1);
}

TEST(JobPool, TheFirstExceptionIsRethrownAfterEveryCallReturned) {
  JobPool pool(3);
  std::atomic<int> returned{0};
  try {
    pool.for_each(1000, [&](std::size_t i) {
      if (i == 500) throw std::runtime_error("item 500");
      returned.fetch_add(1);
    });
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "item 500");
  }
  EXPECT_EQ(returned.load(), 999);
  // The pool works on after it.
  std::atomic<long> sum{0};
  pool.for_each(100, [&](std::size_t i) { sum.fetch_add(static_cast<long>(i)); });
  EXPECT_EQ(sum.load(), 4950);
}

TEST(JobPool, ZeroThreadsMeansEveryCore) {
  EXPECT_EQ(threads_or_all(0), hardware_threads());
  EXPECT_EQ(threads_or_all(3), 3);
  EXPECT_GE(hardware_threads(), 1);
}

}  // namespace
}  // namespace rhot
