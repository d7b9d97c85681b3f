// A recording played back as tracking results: past its end the last frame is held, and the
// playback says once, naming the file, at which frame and time of the run the recording ended.

#include "engine/tracked/ReplaySource.h"

#include <string>

#include <gtest/gtest.h>

namespace rhot {
namespace {

// Three frames, 0.1 s apart, the right hand's joints moving 0.1 m along X a frame.
std::string three_frames(const std::string& name) {
  const std::string file = ::testing::TempDir() + name;
  auto writer = RecordingWriter::open(file, 10.0, {});
  EXPECT_TRUE(writer.has_value()) << writer.error();
  for (int f = 0; f < 3; ++f) {
    RecordedFrame frame;
    frame.t_s = 0.1 * f;
    frame.hands[1].seen = true;
    for (auto& p : frame.hands[1].joints_world) p = Eigen::Vector3d(0.1 * f, 1.0, -0.5);
    EXPECT_TRUE(writer->write(frame).has_value());
  }
  return file;
}

TEST(ReplaySource, TheEndOfTheRecordingIsSaidOnceAndItsLastFrameHeld) {
  const std::string file = three_frames("rhot_replay_end.jsonl");
  auto replay = ReplaySource::open(file, 1.0, TrackedObjects{});
  ASSERT_TRUE(replay.has_value()) << replay.error();
  ReplaySource& source = **replay;
  for (const double t : {0.0, 0.1, 0.2}) {
    source.replay(t);
    EXPECT_FALSE(source.end_notice().has_value()) << "at " << t << " s the recording still plays";
    EXPECT_NEAR(source.results().hands[1].joints_world[0].x(), t, 1e-9);
  }
  source.replay(0.3);
  const std::string said = "replay: the recording " + file +
                           " ended at frame 4 of the run (0.300 s): its 3 frames (0.200 s) have played, and its last frame is held from "
                           "here on";
  ASSERT_TRUE(source.end_notice().has_value());
  EXPECT_EQ(*source.end_notice(), said);
  source.replay(0.4);
  EXPECT_EQ(*source.end_notice(), said) << "said once, where it ended";
  EXPECT_NEAR(source.results().hands[1].joints_world[0].x(), 0.2, 1e-12) << "the last frame is held";
  EXPECT_FALSE(source.ended()) << "the run goes on";
}

TEST(ReplaySource, AtTwiceTheSpeedTheRecordingEndsHalfwayThroughTheTime) {
  const std::string file = three_frames("rhot_replay_fast.jsonl");
  auto replay = ReplaySource::open(file, 2.0, TrackedObjects{});
  ASSERT_TRUE(replay.has_value()) << replay.error();
  ReplaySource& source = **replay;
  source.replay(0.0);
  source.replay(0.1);
  EXPECT_FALSE(source.end_notice().has_value());
  source.replay(0.15);
  ASSERT_TRUE(source.end_notice().has_value());
  EXPECT_EQ(*source.end_notice(), "replay: the recording " + file +
                                      " ended at frame 3 of the run (0.150 s): its 3 frames (0.200 s) have played, and its last frame is "
                                      "held from here on");
}

}  // namespace
}  // namespace rhot
