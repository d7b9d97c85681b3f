// rhot-demo --stream: the real demo sends its frames to liblo's server on loopback, live and from
// a recording; a bad destination is one clear line.

#include <algorithm>
#include <filesystem>
#include <lo/lo.h>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "engine/tracked/Recording.h"
#include "tests/support/OscReceiver.h"
#include "tests/support/RunCommand.h"

namespace {

namespace fs = std::filesystem;

using Message = rhot::test::OscReceived;

// The demo's destination for a receiver.
std::string url_of(const rhot::test::OscReceiver& receiver, bool vmc) {
  return "osc://127.0.0.1:" + std::to_string(receiver.port()) + (vmc ? ",vmc" : "");
}

fs::path temp_dir() {
  const fs::path d = fs::path(::testing::TempDir()) / "rhot_stream_cli" / ::testing::UnitTest::GetInstance()->current_test_info()->name();
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

// The default demo for 30 frames: a bundle for every frame the sender took, each with its frame
// counter, the VMC header and 16 bones of each hand seen. (Headless, the demo runs its frames as
// fast as it can; on a busy machine the sender may find a newer frame waiting and skip the older
// one, which the demo reports.)
TEST(StreamCli, TheDemoStreamsItsFramesAsVmc) {
  rhot::test::OscReceiver receiver;
  const auto demo = rhot::test::run_program("rhot-demo", "--headless --frames 30 --eye 64x64 --stream " + url_of(receiver, true), "2>&1");
  ASSERT_EQ(demo.exit_code, 0) << demo.output;
  const auto counts = demo.output.find(": 30 frames, ");
  ASSERT_NE(counts, std::string::npos) << demo.output;
  const int sent = std::stoi(demo.output.substr(counts + 13));
  EXPECT_NE(demo.output.find(std::to_string(sent) + " sent, " + std::to_string(30 - sent) + " skipped (the sender was busy), 0 failed"),
            std::string::npos)
      << demo.output;
  EXPECT_GE(sent, 10);
  const std::vector<Message>& got = receiver.drain();
  std::vector<double> frames;
  int ok = 0, left_hands = 0, bones = 0;
  for (const Message& m : got) {
    if (m.path == "/rhot/frame") frames.push_back(m.numbers[0]);
    if (m.path == "/VMC/Ext/OK") ++ok;
    if (m.path == "/VMC/Ext/Bone/Pos") {
      ++bones;
      if (m.strings[0] == "LeftHand") ++left_hands;
    }
  }
  ASSERT_EQ(frames.size(), static_cast<std::size_t>(sent));
  EXPECT_GE(frames.front(), 0.0);
  for (std::size_t f = 1; f < frames.size(); ++f) EXPECT_GT(frames[f], frames[f - 1]);
  EXPECT_LE(frames.back(), 29.0);
  EXPECT_EQ(ok, sent);
  EXPECT_GE(left_hands, sent - 5);
  EXPECT_EQ(bones % 16, 0);
}

// A recording replayed with --stream: the joints that arrive are the recording's.
TEST(StreamCli, AReplayStreamsTheRecordedJoints) {
  const fs::path dir = temp_dir();
  const fs::path rec = dir / "session.jsonl";
  const auto recorded = rhot::test::run_program("rhot-demo", "--headless --frames 40 --eye 64x64 --record " + rec.string(), "2>&1");
  ASSERT_EQ(recorded.exit_code, 0) << recorded.output;
  const auto recording = rhot::load_recording(rec);
  ASSERT_TRUE(recording.has_value()) << recording.error();

  rhot::test::OscReceiver receiver;
  const auto replay = rhot::test::run_program(
      "rhot-demo", "--headless --frames 30 --eye 64x64 --source replay:" + rec.string() + " --stream " + url_of(receiver, false), "2>&1");
  ASSERT_EQ(replay.exit_code, 0) << replay.output;
  int checked = 0;
  for (const Message& m : receiver.drain()) {
    if (m.path != "/rhot/hand/joint" || m.strings[0] != "right" || m.strings[1] != "index_tip") continue;
    const Eigen::Vector3d p(m.numbers[0], m.numbers[1], m.numbers[2]);
    double nearest = 1e9;
    for (const rhot::RecordedFrame& f : recording->frames) {
      if (f.hands[1].seen)
        nearest = std::min(nearest, (f.hands[1].joints_world[static_cast<std::size_t>(rhot::HandJoint::kIndexTip)] - p).norm());
    }
    EXPECT_LT(nearest, 1e-5);
    ++checked;
  }
  EXPECT_GE(checked, 10);
}

TEST(StreamCli, ABadDestinationIsOneClearLine) {
  auto r = rhot::test::run_program("rhot-demo", "--headless --frames 3 --eye 64x64 --stream udp://localhost:9000", "2>&1");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("--stream: expected osc://HOST:PORT or osc://HOST:PORT,vmc, got \"udp://localhost:9000\""), std::string::npos)
      << r.output;
  r = rhot::test::run_program("rhot-demo", "--headless --frames 3 --eye 64x64 --stream osc://no-such-host.invalid:9000", "2>&1");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("--stream: host \"no-such-host.invalid\" does not resolve"), std::string::npos) << r.output;
}

}  // namespace
