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
  std::atomic<bool> done{false};
  std::thread publisher([&] {
    for (std::uint64_t f = 2; f < 20000; ++f) (*writer)->publish(frame_snapshot(f));
    done = true;
  });
  HandShareReader reader(name, 0.0);
  int reads = 0, inconsistent = 0;
  std::uint64_t last = 0;
  bool backwards = false;
  while (!done.load()) {
    if (const auto s = reader.read(steady_now_s())) {
      ++reads;
      inconsistent += consistent(*s) ? 0 : 1;
      backwards = backwards || s->frame < last;
      last = s->frame;
    }
  }
  publisher.join();
  EXPECT_GT(reads, 100);
  EXPECT_EQ(inconsistent, 0);
  EXPECT_FALSE(backwards);
  const auto final_read = reader.read(steady_now_s());
  ASSERT_TRUE(final_read.has_value());
  EXPECT_EQ(final_read->frame, 19999u);
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
