// Recordings read back: every problem named by file and line (each line is a JSON document of its
// own), with the JSON pointer of the bad value.

#include "engine/tracked/Recording.h"

#include <array>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

namespace rhot {
namespace {

// One frame's line as RecordingWriter writes it (no hands seen, no objects).
std::string written_frame_line() {
  const std::string file = ::testing::TempDir() + "rhot_one_frame.jsonl";
  {
    auto writer = RecordingWriter::open(file, 90.0, {});
    EXPECT_TRUE(writer.has_value());
    EXPECT_TRUE(writer->write(RecordedFrame{}).has_value());
  }
  std::ifstream in(file);
  std::string header, line;
  std::getline(in, header);
  std::getline(in, line);
  return line;
}

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
  // A grasp event of a kind recordings do not hold.
  {
    std::ofstream out(file);
    out << R"({"format": "rhot-recording", "version": 1, "rate_hz": 90, "objects": []})"
        << "\n";
    out << written_frame_line() << "\n";
    std::string line = written_frame_line();
    line.replace(line.rfind('}'), 1, R"(, "grasp_events": [{"type": "squeeze", "hand": "right", "object": "cup", "reason": ""}]})");
    out << line << "\n";
  }
  EXPECT_EQ(load_recording(file).error(), file + ":3: /grasp_events/0/type: expected \"grasp\" or \"release\", got \"squeeze\"");
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
      if (f == 1) {
        frame.holding[1] = "cup";
        frame.grasp_events.push_back({"grasp", "right", "cup", "thumb against index (index not measured)"});
      }
      ASSERT_TRUE(writer->write(frame).has_value());
    }
  }
  const auto r = load_recording(file);
  ASSERT_TRUE(r.has_value()) << r.error();
  EXPECT_EQ(r->objects, std::vector<std::string>{"cup"});
  ASSERT_EQ(r->frames.size(), 3u);
  EXPECT_DOUBLE_EQ(r->rate_hz, 90.0);
  EXPECT_NEAR(r->duration_s(), 0.2, 1e-12);
  // What the hands held, and why they grasped, only where there was something.
  EXPECT_EQ(r->frames[0].holding, (std::array<std::string, 2>{"", ""}));
  EXPECT_EQ(r->frames[1].holding, (std::array<std::string, 2>{"", "cup"}));
  EXPECT_EQ(r->frames[1].grasp_events,
            (std::vector<RecordedGraspEvent>{{"grasp", "right", "cup", "thumb against index (index not measured)"}}));
  EXPECT_TRUE(r->frames[2].grasp_events.empty());
  // Halfway between frames 1 and 2: positions interpolated linearly.
  const RecordedFrame mid = r->at(0.15);
  EXPECT_NEAR(mid.hands[1].joints_world[0].x(), 0.15, 1e-12);
  EXPECT_NEAR(mid.objects.at("cup").translation.y(), 0.3, 1e-12);
  EXPECT_FALSE(mid.hands[0].seen);
  // Clamped at both ends.
  EXPECT_NEAR(r->at(-1.0).hands[1].joints_world[0].x(), 0.0, 1e-12);
  EXPECT_NEAR(r->at(9.0).hands[1].joints_world[0].x(), 0.2, 1e-12);
}

// The text of a recording of `frames` frames, 0.1 s apart, written by RecordingWriter: a header line
// and one line per frame, each ending in a newline.
std::string written_recording(const std::string& file, int frames) {
  {
    auto writer = RecordingWriter::open(file, 90.0, {"cup"});
    EXPECT_TRUE(writer.has_value()) << writer.error();
    for (int f = 0; f < frames; ++f) {
      RecordedFrame frame;
      frame.t_s = 0.1 * f;
      frame.hands[1].seen = true;
      for (auto& p : frame.hands[1].joints_world) p = Eigen::Vector3d(0.1 * f, 1.0, -0.5);
      EXPECT_TRUE(writer->write(frame).has_value());
    }
  }
  std::ifstream in(file, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// A crash while a frame is written leaves its line cut short, without its newline (the docs promise
// that a crash loses at most that frame): the frames before it are read, and one warning names the
// file and the line.
TEST(Recording, ALastLineCutShortByACrashIsLeftOutWithAWarning) {
  const std::string file = ::testing::TempDir() + "rhot_cut_recording.jsonl";
  const std::string text = written_recording(file, 4);
  ASSERT_EQ(text.back(), '\n');
  const std::size_t last_line = text.rfind('\n', text.size() - 2) + 1;
  std::ofstream(file, std::ios::binary) << text.substr(0, last_line + 40);  // frame 4 on line 5, cut 40 bytes in
  const auto r = load_recording(file);
  ASSERT_TRUE(r.has_value()) << r.error();
  EXPECT_EQ(r->frames.size(), 3u);
  EXPECT_NEAR(r->frames.back().t_s, 0.2, 1e-12);
  EXPECT_EQ(r->warnings, std::vector<std::string>{file + ":5: the last line is cut short (was the recording interrupted?); it is left out, "
                                                         "the 3 frames before it are read"});

  // Cut right after the header's newline plus a byte: no frame is whole.
  std::ofstream(file, std::ios::binary) << text.substr(0, text.find('\n') + 2);
  EXPECT_EQ(load_recording(file).error(), file + ": no frames");

  // A whole recording reads without a warning.
  std::ofstream(file, std::ios::binary) << text;
  ASSERT_TRUE(load_recording(file).has_value());
  EXPECT_TRUE(load_recording(file)->warnings.empty());
}

// Only a last line that is not even JSON counts as cut short: a line cut in the middle of the file,
// or a last line that is whole JSON but no frame, is an error naming its line.
TEST(Recording, ABadLineBeforeTheLastOrAWholeBadLastLineIsStillAnError) {
  const std::string file = ::testing::TempDir() + "rhot_bad_middle_recording.jsonl";
  const std::string text = written_recording(file, 4);
  const std::size_t third = text.find('\n', text.find('\n', text.find('\n') + 1) + 1) + 1;  // the start of line 4
  std::ofstream(file, std::ios::binary) << text.substr(0, third - 30) << "\n" << text.substr(third);
  const auto middle = load_recording(file);
  ASSERT_FALSE(middle.has_value());
  EXPECT_EQ(middle.error().rfind(file + ":3:1:", 0), 0u) << middle.error();
  EXPECT_NE(middle.error().find(": invalid JSON: "), std::string::npos) << middle.error();

  std::ofstream(file, std::ios::binary) << text << R"({"t": 0.5, "hands": [], "objects": {}})";  // no newline, but whole
  EXPECT_EQ(load_recording(file).error(), file + ":6: /hands: expected [left, right]");
}

}  // namespace
}  // namespace rhot
