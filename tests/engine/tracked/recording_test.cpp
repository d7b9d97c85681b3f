// Recordings read back: every problem named by file and line (each line is a JSON document of its
// own), with the JSON pointer of the bad value.

#include "engine/tracked/Recording.h"

#include <fstream>

#include <gtest/gtest.h>

namespace rhot {
namespace {

TEST(Recording, BrokenRecordingsAreRefusedNamingTheLine) {
  const std::string file = ::testing::TempDir() + "rhot_bad_recording.jsonl";
  {
    std::ofstream out(file);
    out << R"({"format": "rhot-recording", "version": 1, "rate_hz": 90, "objects": []})"
        << "\n";
    out << R"({"t": 0.0, "hands": [], "objects": {}})"
        << "\n";
  }
  const auto r = load_recording(file);
  ASSERT_FALSE(r.has_value());
  EXPECT_EQ(r.error(), file + ":2: /hands: expected [left, right]");
  {
    std::ofstream out(file);
    out << R"({"format": "rhot-recording", "version": 2, "rate_hz": 90})"
        << "\n";
  }
  EXPECT_EQ(load_recording(file).error(), file + ":1: /version: expected an integer from 1 to 1, got 2");
  EXPECT_EQ(load_recording(file + ".missing").error(), file + ".missing: cannot read the recording");
}

TEST(Recording, AWrittenRecordingReadsBackAndInterpolates) {
  const std::string file = ::testing::TempDir() + "rhot_recording_round_trip.jsonl";
  {
    auto writer = RecordingWriter::open(file, 90.0, {"cup"});
    ASSERT_TRUE(writer.has_value()) << writer.error();
    for (int f = 0; f < 3; ++f) {
      RecordedFrame frame;
      frame.t_s = 0.1 * f;
      frame.hands[1].seen = true;
      frame.hands[1].world_from_hand.translation = Eigen::Vector3d(0.1 * f, 1.0, 0.0);
      for (auto& p : frame.hands[1].joints_world) p = Eigen::Vector3d(0.1 * f, 1.0, -0.5);
      frame.objects["cup"].translation = Eigen::Vector3d(0.0, 0.2 * f, 0.0);
      ASSERT_TRUE(writer->write(frame).has_value());
    }
  }
  const auto r = load_recording(file);
  ASSERT_TRUE(r.has_value()) << r.error();
  EXPECT_EQ(r->objects, std::vector<std::string>{"cup"});
  ASSERT_EQ(r->frames.size(), 3u);
  EXPECT_DOUBLE_EQ(r->rate_hz, 90.0);
  EXPECT_NEAR(r->duration_s(), 0.2, 1e-12);
  // Halfway between frames 1 and 2: positions interpolated linearly.
  const RecordedFrame mid = r->at(0.15);
  EXPECT_NEAR(mid.hands[1].joints_world[0].x(), 0.15, 1e-12);
  EXPECT_NEAR(mid.objects.at("cup").translation.y(), 0.3, 1e-12);
  EXPECT_FALSE(mid.hands[0].seen);
  // Clamped at both ends.
  EXPECT_NEAR(r->at(-1.0).hands[1].joints_world[0].x(), 0.0, 1e-12);
  EXPECT_NEAR(r->at(9.0).hands[1].joints_world[0].x(), 0.2, 1e-12);
}

}  // namespace
}  // namespace rhot
