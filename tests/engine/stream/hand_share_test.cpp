// The hands in shared memory (engine/stream/HandShare.h): a reader never sees half of one frame
// and half of another, finds a block made after it, and sees a stopped writer stop.

#include <fcntl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <atomic>
#include <cstring>
#include <string>
#include <thread>

#include <gtest/gtest.h>

#include "base/SteadyClock.h"
#include "engine/stream/HandShare.h"

namespace rhot {
namespace {

std::string unique_name(const char* what) { return std::string("/rhot-test-") + what + "-" + std::to_string(getpid()); }

// Every number in the snapshot is the frame's.
HandShareSnapshot frame_snapshot(std::uint64_t frame) {
  HandShareSnapshot s{};
  s.frame = frame;
  s.capture_s = s.published_s = static_cast<double>(frame);
  for (HandShareHand& h : s.hands) {
    h.tracked = 1;
    for (HandShareJoint& j : h.joints) {
      for (float& x : j.position) x = static_cast<float>(frame);
      j.radius = static_cast<float>(frame);
    }
  }
  return s;
}

bool consistent(const HandShareSnapshot& s) {
  const auto f = static_cast<float>(s.frame);
  for (const HandShareHand& h : s.hands) {
    for (const HandShareJoint& j : h.joints) {
      if (j.position[0] != f || j.position[1] != f || j.position[2] != f || j.radius != f) return false;
    }
  }
  return s.capture_s == static_cast<double>(s.frame);
}

TEST(HandShare, AReaderNeverSeesHalfOfOneFrameAndHalfOfAnother) {
  const std::string name = unique_name("torn");
  auto writer = HandShareWriter::open(name);
  ASSERT_TRUE(writer.has_value()) << writer.error();
  (*writer)->publish(frame_snapshot(1));
  std::atomic<bool> stop{false};
  std::atomic<std::uint64_t> published{1};
  std::thread publisher([&] {
    for (std::uint64_t f = 2; !stop.load(); ++f) {
      (*writer)->publish(frame_snapshot(f));
      published = f;
    }
  });
  // Reads while the frames come, until 2,000 of them were taken during at least 1,000 frames
  // written (or 20 s: a machine that slow fails the counts below).
  HandShareReader reader(name, 0.0);
  int reads = 0, inconsistent = 0;
  std::uint64_t last = 0;
  bool backwards = false;
  const double start = steady_now_s();
  while ((reads < 2000 || published.load() < 1000) && steady_now_s() - start < 20.0) {
    if (const auto s = reader.read(steady_now_s())) {
      ++reads;
      inconsistent += consistent(*s) ? 0 : 1;
      backwards = backwards || s->frame < last;
      last = s->frame;
    }
  }
  stop = true;
  publisher.join();
  EXPECT_GE(reads, 2000);
  EXPECT_GE(published.load(), 1000u);
  EXPECT_EQ(inconsistent, 0);
  EXPECT_FALSE(backwards);
  const auto final_read = reader.read(steady_now_s());
  ASSERT_TRUE(final_read.has_value());
  EXPECT_EQ(final_read->frame, published.load());
  shm_unlink(name.c_str());
}

TEST(HandShare, AReaderFindsAWriterStartedAfterItAndSeesItStopAndComeBack) {
  const std::string name = unique_name("later");
  shm_unlink(name.c_str());
  HandShareReader reader(name, 0.0);
  EXPECT_FALSE(reader.read(steady_now_s()).has_value());  // no block yet
  {
    auto writer = HandShareWriter::open(name);
    ASSERT_TRUE(writer.has_value()) << writer.error();
    EXPECT_FALSE(reader.read(steady_now_s()).has_value());  // a block, nothing published in it yet
    (*writer)->publish(frame_snapshot(5));
    const auto s = reader.read(steady_now_s());
    ASSERT_TRUE(s.has_value());
    EXPECT_EQ(s->frame, 5u);
  }
  EXPECT_FALSE(reader.read(steady_now_s()).has_value());  // stopped cleanly
  auto again = HandShareWriter::open(name);
  ASSERT_TRUE(again.has_value()) << again.error();
  (*again)->publish(frame_snapshot(6));
  const auto s = reader.read(steady_now_s());
  ASSERT_TRUE(s.has_value());
  EXPECT_EQ(s->frame, 6u);
  shm_unlink(name.c_str());
}

TEST(HandShare, OneWriterAtATimeAndWhatACrashedOneLeftHalfWrittenIsNeverRead) {
  const std::string name = unique_name("owner");
  shm_unlink(name.c_str());
  {
    auto first = HandShareWriter::open(name);
    ASSERT_TRUE(first.has_value()) << first.error();
    auto second = HandShareWriter::open(name);
    ASSERT_FALSE(second.has_value());
    EXPECT_EQ(second.error(), "process " + std::to_string(getpid()) + " is publishing its hands in " + name +
                                  " (start this one with --no-publish, or another RHOT_HANDS_SHM)");
    (*first)->publish(frame_snapshot(3));
  }
  // A writer that died while writing: its sequence left odd, its snapshot half of a new frame.
  const int fd = shm_open(name.c_str(), O_RDWR, 0);
  ASSERT_GE(fd, 0);
  void* mapped = mmap(nullptr, sizeof(HandShareBlock), PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
  close(fd);
  ASSERT_NE(mapped, MAP_FAILED);
  auto* block = static_cast<HandShareBlock*>(mapped);
  block->sequence.fetch_add(1);
  block->snapshot.hands[0].joints[0].position[0] = 4.0f;
  block->running.store(1);
  HandShareReader reader(name, 0.0);
  EXPECT_FALSE(reader.read(steady_now_s()).has_value());  // an odd sequence is never taken
  // The next writer clears it: nothing tracked until it publishes.
  auto next = HandShareWriter::open(name);
  ASSERT_TRUE(next.has_value()) << next.error();
  EXPECT_EQ(block->sequence.load() % 2, 0u);
  EXPECT_EQ(block->snapshot.hands[0].tracked, 0u);
  EXPECT_FALSE(reader.read(steady_now_s()).has_value());
  (*next)->publish(frame_snapshot(4));
  const auto s = reader.read(steady_now_s());
  ASSERT_TRUE(s.has_value());
  EXPECT_TRUE(consistent(*s));
  munmap(mapped, sizeof(HandShareBlock));
  shm_unlink(name.c_str());
}

TEST(HandShare, ABlockOfAnotherFormatIsNotReadAndAWriterLaysItOutAnew) {
  const std::string name = unique_name("format");
  const int fd = shm_open(name.c_str(), O_RDWR | O_CREAT | O_TRUNC, 0644);
  ASSERT_GE(fd, 0);
  std::string garbage(sizeof(HandShareBlock), '\x5a');
  ASSERT_EQ(write(fd, garbage.data(), garbage.size()), static_cast<ssize_t>(garbage.size()));
  close(fd);
  HandShareReader reader(name, 0.0);
  EXPECT_FALSE(reader.read(steady_now_s()).has_value());
  auto writer = HandShareWriter::open(name);
  ASSERT_TRUE(writer.has_value()) << writer.error();
  (*writer)->publish(frame_snapshot(9));
  const auto s = reader.read(steady_now_s());
  ASSERT_TRUE(s.has_value());
  EXPECT_TRUE(consistent(*s));
  EXPECT_EQ(s->frame, 9u);
  shm_unlink(name.c_str());
}

}  // namespace
}  // namespace rhot
