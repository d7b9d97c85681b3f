// Camera nodes under a minute of chaos (rhot-eval nodes --chaos, tools/eval/Chaos.h): real node
// processes on loopback, killed, restarted, impersonated and flooded while the master assembles
// their frames. A program of its own so that it runs beside other tests: the node tests that time
// the transport run alone, this one counts what is lost, not when.

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "tests/support/NodesRun.h"

namespace {

using rhot::test::run_nodes_once;

// A minute of faults together (tools/eval/Chaos.h): nodes killed and restarted with new clocks and
// slow links, an impostor at a dead node's endpoint, junk and oversized messages at the nodes, the
// master's receiving thread stalled. No frame is lost while every node serves, no marker but a
// node's is ever taken, every node comes back, and the master's heap does not grow.
TEST(NodesCli, AMinuteOfChaosLosesNoFrameWhileEveryNodeServesAndTakesNoFalseMarker) {
  // One run: a machine that stalls skips exposures, which the count of frames lost while every
  // node served leaves out, so the run is not repeated.
  const nlohmann::json j = run_nodes_once("--chaos 60 --seed 5");
  ASSERT_TRUE(j.contains("frames_lost_while_all_up")) << j.dump();
  EXPECT_EQ(j["security"], "curve");
  EXPECT_EQ(j["frames_lost_while_all_up"], 0) << j.dump(2);
  EXPECT_EQ(j["wrong_markers_accepted"], 0) << j.dump(2);
  EXPECT_EQ(j["bad_messages"], 0) << "nothing the impostor sent reached the decoder\n" << j.dump(2);
  EXPECT_GE(j["kills"].get<int>(), 10) << j.dump(2);
  EXPECT_GE(j["stalls"].get<int>(), 5) << j.dump(2);
  EXPECT_GT(j["impostor_frames_sent"].get<int>(), 100) << j.dump(2);
  EXPECT_GT(j["handshakes_failed"].get<int>(), 0) << "the impostor was tried and refused\n" << j.dump(2);
  EXPECT_EQ(j["never_rejoined"], 0) << j.dump(2);
  // A restarted node is heard within a fraction of a second of starting (under AddressSanitizer,
  // its start takes most of that).
  EXPECT_LT(j["rejoin_p99_s"].get<double>(), 2.0) << j.dump(2);
  EXPECT_LT(j["memory_growth_fraction"].get<double>(), 0.10) << j.dump(2);
  EXPECT_GT(j["frames_with_camera_missing"].get<int>(), 0) << "the faults were felt\n" << j.dump(2);
}

}  // namespace
