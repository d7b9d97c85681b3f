// Camera nodes as real processes on loopback: rhot-eval nodes starts rhot-node processes that
// simulate the cameras of a rig and assembles their frames; these tests read its JSON. All
// traffic stays on 127.0.0.1.

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <regex>
#include <string>
#include <utility>
#include <vector>

#include <unistd.h>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "tests/support/NodesRun.h"
#include "tests/support/Sanitizers.h"
#include "tests/support/RunCommand.h"
#include "tracking/net/ChildProcess.h"
#include "tracking/net/NodeSource.h"

namespace {

using rhot::test::run_nodes;

// Frames a loaded 2-core machine may lose or see incomplete to scheduling. Under AddressSanitizer
// (CI's build) every process runs two to three times slower, so a few frames more miss the
// assembly deadline there; the release build holds the tight figure.
#if RHOT_ASAN
constexpr int kSchedulingSlackFrames = 8;
constexpr double kFoundFloor = 0.96;
constexpr double kHandsSeenFloor = 0.98;
#else
constexpr int kSchedulingSlackFrames = 2;
constexpr double kFoundFloor = 0.98;
constexpr double kHandsSeenFloor = 0.99;
#endif

// Frames lost on the way: at most `transport` (the machine's scheduling), however many exposures
// the nodes themselves skipped (a node behind real time skips to the present; a whole-machine
// stall of 100 ms skips the same nine exposures on every node, which no transport can deliver).
// Those are few too: a tenth of the run at most.
void expect_few_lost(const nlohmann::json& j, int transport) {
  ASSERT_TRUE(j.contains("frames_lost_in_transport")) << j.dump(2);
  EXPECT_LE(j["frames_lost_in_transport"].get<int>(), transport) << j.dump(2);
  EXPECT_EQ(j["frames_lost"].get<int>(), j["frames_lost_in_transport"].get<int>() + j["frames_not_made"].get<int>());
  EXPECT_LE(j["frames_lost"].get<int>(), j["frames_expected"].get<int>() / 10) << j.dump(2);
}

TEST(NodesCli, FourNodesDeliverEveryFrameAndTheMarkersAreFoundAsFromLocalCameras) {
  const nlohmann::json j = run_nodes("--nodes 4 --markers 40 --seconds 2");
  ASSERT_TRUE(j.contains("frames_expected")) << j.dump();
  EXPECT_EQ(j["frames_expected"], 180);
  // A loaded 2-core machine may lose a frame or two to scheduling, no more.
  expect_few_lost(j, kSchedulingSlackFrames);
  EXPECT_GT(j["found_fraction"].get<double>(), kFoundFloor) << j.dump(2);
  EXPECT_EQ(j["bad_messages"], 0);
  // Secure by default: keys made for the run, every handshake through at the first try.
  EXPECT_EQ(j["security"], "curve");
  EXPECT_EQ(j["handshakes_failed"], 0) << j.dump(2);
  EXPECT_GE(j["handshake_median_ms"].get<double>(), 0.0) << j.dump(2);
  EXPECT_LT(j["handshake_max_ms"].get<double>(), 1000.0) << j.dump(2);
  // A round trip's sample is at most half its round trip off, so neither the offset (checked
  // against the truth: the nodes share this host's clock) nor the fit's residual can honestly be
  // held below that: 100 us where round trips take 60-100 us (the release build), half the
  // fastest round trip under AddressSanitizer, whose round trips take 360-470 us on a loaded
  // machine.
  const auto bound_us = [](const nlohmann::json& node) { return std::max(100.0, 0.5 * node["min_rtt_us"].get<double>()); };
  EXPECT_LT(j["clock_offset_error_us"].get<double>(), bound_us(j["per_node"][0])) << j.dump(2);
  for (const auto& n : j["per_node"]) {
    EXPECT_GT(n["frames"].get<int>(), 300) << n.dump();
    EXPECT_LT(n["clock_residual_us"].get<double>(), bound_us(n)) << n.dump();
  }
}

TEST(NodesCli, AKilledNodeLeavesTrackingToTheOthersAndComesBackWhenRestarted) {
  // room-8: node 3 of 4 serves cameras 3 and 7; the other six still see nearly every marker.
  const nlohmann::json j = run_nodes("--nodes 4 --markers 40 --seconds 4 --kill-node-at 1 --restart-node-at 2.2");
  ASSERT_TRUE(j.contains("rejoined")) << j.dump();
  EXPECT_GT(j["found_fraction_while_node_down"].get<double>(), 0.95) << j.dump(2);
  EXPECT_TRUE(j["rejoined"].get<bool>()) << j.dump(2);
  expect_few_lost(j, 4);  // frames go on while the node is down
  EXPECT_EQ(j["per_node"][3]["lost"], 1);
  EXPECT_EQ(j["per_node"][3]["rejoined"], 1);
}

TEST(NodesCli, ANodeClockFiftyMillisecondsAheadAndDriftingIsSynchronised) {
  const nlohmann::json j = run_nodes("--nodes 2 --markers 20 --seconds 3 --clock-offset-ms 50 --clock-drift-ppm 100");
  ASSERT_TRUE(j.contains("clock_offset_error_us")) << j.dump();
  EXPECT_LT(j["clock_offset_error_us"].get<double>(), 100.0) << j.dump(2);
  EXPECT_NEAR(j["per_node"][0]["clock_offset_ms"].get<double>(), 50.3, 0.1) << j.dump(2);
  // Frames are assembled from both nodes (a 50 ms error would split every group in two).
  EXPECT_GT(j["found_fraction"].get<double>(), 0.95) << j.dump(2);
  expect_few_lost(j, 3);
}

TEST(NodesCli, ANodeDelayedThirtyMillisecondsIsLeftOutOfFramesThatCannotWaitAndCounted) {
  const nlohmann::json j = run_nodes("--nodes 2 --markers 20 --seconds 2 --delay-ms 30 --deadline-ms 20");
  ASSERT_TRUE(j.contains("late")) << j.dump();
  // Node 0's every frame arrives after its group closed (30 ms against a 20 ms deadline, which
  // leaves node 1's own messages room under AddressSanitizer on a loaded machine: at 10 ms, 15
  // frames of node 1 came too late in one CI run): about one per frame, all counted.
  EXPECT_GT(j["late"].get<int>(), 150) << j.dump(2);
  expect_few_lost(j, 2);  // no frame waits for it
  EXPECT_LT(j["frames_complete"].get<int>(), 5) << j.dump(2);
}

TEST(NodesCli, FourNodesServingTheDemoTrackTheHandsAsWellAsTheInProcessSimulatedRig) {
  // The demo's script photographed by four node processes (one camera each of the seated rig), its
  // hands tracked from their frames and, at the same moments, from the in-process simulated rig.
  const nlohmann::json j = run_nodes(std::string("--nodes 4 --rig ") + RHOT_ASSET_DIR + "/rigs/seated-4.yaml --scene " + RHOT_ASSET_DIR +
                                     "/scenes/default.json --seconds 6");
  ASSERT_TRUE(j.contains("hand_joint_mean_mm")) << j.dump();
  const double nodes = j["hand_joint_mean_mm"].get<double>(), local = j["in_process_hand_joint_mean_mm"].get<double>();
  EXPECT_GT(local, 1.0) << "a real error to compare with";
  EXPECT_LE(nodes, 1.10 * local) << j.dump(2);
  EXPECT_GT(j["hands_seen_fraction"].get<double>(), kHandsSeenFloor) << j.dump(2);
  // The in-process rig sees the cameras each assembled frame had: a late camera hides a hand from both.
  EXPECT_GT(j["in_process_hands_seen_fraction"].get<double>(), kHandsSeenFloor) << j.dump(2);
  // Each side's spread over its hand-frames, and when its worst frame was: within the 6 s run, its
  // worst frame above its 95th percentile, which is above the run's mean (the frames' errors are
  // not all equal).
  for (const std::string side : {"", "in_process_"}) {
    const double p95 = j[side + "hand_frame_p95_mm"].get<double>(), worst = j[side + "hand_frame_max_mm"].get<double>();
    EXPECT_GT(p95, j[side + "hand_joint_mean_mm"].get<double>()) << side;
    EXPECT_GE(worst, p95) << side;
    EXPECT_GE(j[side + "hand_frame_max_at_s"].get<double>(), 0.0) << side;
    EXPECT_LE(j[side + "hand_frame_max_at_s"].get<double>(), 6.0) << side;
  }
}

// Key folders made as a user makes them (rhot-node keygen), in a temporary folder removed at the
// end: master/ and node<i>/, each node trusting the master and the master every node; intruder/,
// a master whose key no node lists.
class KeyFolders {
 public:
  explicit KeyFolders(int nodes) : dir_(std::filesystem::temp_directory_path() / ("rhot-nodes-cli-keys-" + std::to_string(::getpid()))) {
    std::filesystem::remove_all(dir_);
    make("master");
    make("intruder");
    for (int i = 0; i < nodes; ++i) {
      const std::string node = "node" + std::to_string(i);
      make(node);
      trust("master", node);
      trust("intruder", node);
      trust(node, "master");
    }
  }
  ~KeyFolders() {
    std::error_code ec;
    std::filesystem::remove_all(dir_, ec);
  }
  std::string operator[](const std::string& name) const { return (dir_ / name).string(); }

 private:
  void make(const std::string& name) {
    const auto r = rhot::test::run_program("rhot-node", "keygen --out " + (*this)[name] + " --name " + name, "2>&1");
    EXPECT_EQ(r.exit_code, 0) << r.output;
    std::filesystem::create_directories(dir_ / name / "trusted");
  }
  void trust(const std::string& who, const std::string& whom) {
    std::filesystem::copy_file(dir_ / whom / (whom + ".key"), dir_ / who / "trusted" / (whom + ".key"),
                               std::filesystem::copy_options::overwrite_existing);
  }
  std::filesystem::path dir_;
};

TEST(NodesCli, TheDemoRunsOnFourNodeProcessesWithKeysAndNeitherAnUntrustedMasterNorAnImpostorNodeGetsThrough) {
  // rhot-demo --source nodes:... on four rhot-node processes photographing its world, with keys
  // made by rhot-node keygen: every frame is assembled from all four cameras, and the demo's own
  // run is unchanged (exit 0, stats). A master whose key the nodes do not list gets no frame, and
  // the nodes say they refused it.
  const KeyFolders keys(4);
  const auto ports = rhot::free_tcp_port_pairs(4);
  ASSERT_TRUE(ports.has_value()) << ports.error();
  const std::string bin = RHOT_BINARY_DIR;
  const std::string start = std::to_string(rhot::steady_now_ns() + 1'000'000'000);
  const std::filesystem::path log = std::filesystem::temp_directory_path() / ("rhot-nodes-cli-" + std::to_string(::getpid()) + ".log");
  std::vector<rhot::ChildProcess> nodes;
  std::string endpoints;
  for (int i = 0; i < 4; ++i) {
    const std::string node = "node" + std::to_string(i);
    const std::string endpoint = "tcp://127.0.0.1:" + std::to_string((*ports)[static_cast<std::size_t>(i)]);
    auto child =
        rhot::ChildProcess::spawn({bin + "/rhot-node", "--publish", endpoint, "--node-id", std::to_string(i), "--sim-rig",
                                   std::string(RHOT_ASSET_DIR) + "/rigs/seated-4.yaml", "--sim-camera", std::to_string(i), "--sim-scene",
                                   std::string(RHOT_ASSET_DIR) + "/scenes/default.json", "--sim-start-ns", start, "--keys", keys[node]},
                                  i == 0 ? log.string() : "/dev/null");
    ASSERT_TRUE(child.has_value()) << child.error();
    nodes.push_back(std::move(*child));
    endpoints += (i ? "," : "") + node + "@" + endpoint;
  }
  const auto r = rhot::test::run_program(
      "rhot-demo", "--headless --frames 150 --eye 64x64 --source nodes:" + endpoints + " --keys " + keys["master"], "2>&1");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  std::smatch m;
  ASSERT_TRUE(std::regex_search(r.output, m, std::regex(R"(assembly: (\d+) frames \((\d+) complete)"))) << r.output;
  EXPECT_GT(std::stoi(m[1]), 100) << r.output;
  // The demo runs as fast as it can beside four node processes: under AddressSanitizer a few
  // per hundred frames miss a camera to the deadline.
  const int slack = std::max(kSchedulingSlackFrames, kSchedulingSlackFrames * std::stoi(m[1]) / 100);
  EXPECT_GE(std::stoi(m[2]), std::stoi(m[1]) - slack) << "all four cameras in (nearly) every frame\n" << r.output;
  EXPECT_EQ(r.output.find("INSECURE"), std::string::npos);

  const auto intruder = rhot::test::run_program(
      "rhot-demo", "--headless --frames 40 --eye 64x64 --source nodes:" + endpoints + " --keys " + keys["intruder"], "2>&1");
  EXPECT_EQ(intruder.exit_code, 0) << intruder.output;
  EXPECT_NE(intruder.output.find("assembly: 0 frames"), std::string::npos) << intruder.output;
  EXPECT_NE(intruder.output.find("refused this master's key"), std::string::npos) << intruder.output;
  for (auto& n : nodes) EXPECT_TRUE(n.running()) << "the nodes outlive both masters";
  // An impostor at node 3's endpoint: a real node process, trusted by nobody as node 3 (it holds
  // node 2's key). The master never hears it, says why, and tracks on with the other three.
  nodes[3].kill();
  const std::string endpoint3 = "tcp://127.0.0.1:" + std::to_string((*ports)[3]);
  auto impostor =
      rhot::ChildProcess::spawn({bin + "/rhot-node", "--publish", endpoint3, "--node-id", "3", "--sim-rig",
                                 std::string(RHOT_ASSET_DIR) + "/rigs/seated-4.yaml", "--sim-camera", "3", "--sim-scene",
                                 std::string(RHOT_ASSET_DIR) + "/scenes/default.json", "--sim-start-ns", start, "--keys", keys["node2"]},
                                "/dev/null");
  ASSERT_TRUE(impostor.has_value()) << impostor.error();
  const auto fooled = rhot::test::run_program(
      "rhot-demo", "--headless --frames 60 --eye 64x64 --source nodes:" + endpoints + " --keys " + keys["master"], "2>&1");
  EXPECT_EQ(fooled.exit_code, 0) << fooled.output;
  EXPECT_NE(fooled.output.find("node node3@" + endpoint3 + " (id -1): not connected, 0 frames"), std::string::npos) << fooled.output;
  EXPECT_NE(fooled.output.find("cannot prove it holds node3's secret key"), std::string::npos) << fooled.output;
  EXPECT_NE(fooled.output.find("node node2@"), std::string::npos) << fooled.output;
  ASSERT_TRUE(std::regex_search(fooled.output, m, std::regex(R"(assembly: (\d+) frames)"))) << fooled.output;
  EXPECT_GT(std::stoi(m[1]), 40) << "the other three nodes' frames\n" << fooled.output;
  nodes[0].stop(2.0);
  std::ifstream in(log);
  const std::string node_log((std::istreambuf_iterator<char>(in)), {});
  std::filesystem::remove(log);
  EXPECT_NE(node_log.find("refused a peer at 127.0.0.1 with the key "), std::string::npos) << node_log;
  EXPECT_NE(node_log.find("master connections admitted"), std::string::npos) << node_log;
  // A bad endpoint is one line and exit 1.
  const auto bad = rhot::test::run_program("rhot-demo", "--headless --frames 1 --insecure --source nodes:tcp://127.0.0.1:99999", "2>&1");
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_NE(bad.output.find("--source: endpoint \"tcp://127.0.0.1:99999\": port \"99999\" is not a number from 1 to 65534"),
            std::string::npos)
      << bad.output;
}

// Security is on unless asked off: every program that talks to nodes refuses to start without a
// key folder or --insecure, refuses a folder it cannot use naming the file, and says on every
// start that it runs insecure.
TEST(NodesCli, WithoutKeysOrInsecureNothingStartsAndInsecureIsSaidOnEveryStart) {
  const std::string sim = " --sim-rig " + std::string(RHOT_ASSET_DIR) + "/rigs/seated-4.yaml --sim-camera 0";
  const std::string need =
      "camera nodes need --keys DIR (this program's NAME.key_secret, and the peers' NAME.key in DIR/trusted/; rhot-node keygen makes "
      "them) or --insecure to run without security";
  auto r = rhot::test::run_program("rhot-node", "--publish tcp://127.0.0.1:5601" + sim, "2>&1", "timeout 20");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find(need), std::string::npos) << r.output;
  r = rhot::test::run_program("rhot-demo", "--headless --frames 1 --source nodes:tcp://127.0.0.1:5601", "2>&1", "timeout 20");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find(need), std::string::npos) << r.output;
  r = rhot::test::run_program(
      "rhot-calib",
      "record --rig " + std::string(RHOT_ASSET_DIR) + "/rigs/seated-4.yaml --source nodes:tcp://127.0.0.1:5601 --out /dev/null", "2>&1",
      "timeout 20");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find(need), std::string::npos) << r.output;
  r = rhot::test::run_program("rhot-node", "--publish tcp://127.0.0.1:5601 --keys /nonexistent/keys" + sim, "2>&1", "timeout 20");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("--keys: /nonexistent/keys: no such folder"), std::string::npos) << r.output;
  r = rhot::test::run_program("rhot-node", "--publish tcp://127.0.0.1:5601 --keys /tmp --insecure" + sim, "2>&1", "timeout 20");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("--keys and --insecure: choose one"), std::string::npos) << r.output;
  r = rhot::test::run_program("rhot-demo", "--headless --frames 1 --keys /tmp", "2>&1", "timeout 20");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("--keys: only for camera nodes"), std::string::npos) << r.output;
  const auto ports = rhot::free_tcp_port_pairs(1);
  ASSERT_TRUE(ports.has_value());
  r = rhot::test::run_program("rhot-node", "--publish tcp://127.0.0.1:" + std::to_string((*ports)[0]) + " --insecure --seconds 0.2" + sim,
                              "2>&1", "timeout 20");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("INSECURE: camera nodes without authentication or encryption (--insecure)"), std::string::npos) << r.output;
  r = rhot::test::run_program("rhot-node", "keygen --out /tmp --name 'a b'", "2>&1", "timeout 20");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("keygen: key name \"a b\": only letters, digits, _ . and - (not ' ')"), std::string::npos) << r.output;
}

TEST(NodesCli, BadFlagsGetOneClearLine) {
  auto r = rhot::test::run_program(
      "rhot-node", "--publish tcp://*:5601 --sim-rig " + std::string(RHOT_ASSET_DIR) + "/rigs/seated-4.yaml --sim-camera 0", "2>&1");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("--publish: endpoint \"tcp://*:5601\": \"*\" would listen on every network; name the address to use"),
            std::string::npos)
      << r.output;
  r = rhot::test::run_program(
      "rhot-node", "--publish udp://127.0.0.1:5601 --sim-rig " + std::string(RHOT_ASSET_DIR) + "/rigs/seated-4.yaml --sim-camera 0",
      "2>&1");
  EXPECT_NE(r.output.find("expected tcp://HOST:PORT, ipc://PATH or inproc://NAME"), std::string::npos) << r.output;
  r = rhot::test::run_program(
      "rhot-node",
      "--publish tcp://127.0.0.1:5601 --insecure --sim-rig " + std::string(RHOT_ASSET_DIR) + "/rigs/seated-4.yaml --sim-camera 9", "2>&1");
  EXPECT_NE(r.output.find("--sim-camera: camera 9 is not in"), std::string::npos) << r.output;
  r = rhot::test::run_program("rhot-node", "--help", "2>&1");
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_NE(r.output.find("--clock-drift-ppm"), std::string::npos);
  r = rhot::test::run_program("rhot-eval", "nodes --nodes 9 --json", "2>&1");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("--nodes 9: "), std::string::npos) << r.output;
}

// CLI::Range lets "nan" through (every comparison with it is false), and a node told to stop
// after nan seconds never stopped. Refused, as are infinity and negative times; `timeout` ends the
// node should one run anyway.
TEST(NodesCli, SecondsThatAreNotAFiniteTimeAreRefused) {
  const std::string node = "--publish tcp://127.0.0.1:5601 --sim-rig " + std::string(RHOT_ASSET_DIR) + "/rigs/seated-4.yaml --sim-camera 0";
  for (const auto& [seconds, message] :
       std::vector<std::pair<std::string, std::string>>{{"nan", "--seconds: expected a finite number, got nan"},
                                                        {"inf", "--seconds: expected a finite number, got inf"},
                                                        {"-2", "--seconds: expected 0 or more, got -2"}}) {
    const auto r = rhot::test::run_program("rhot-node", node + " --seconds " + seconds, "2>&1", "timeout 20");
    EXPECT_EQ(r.exit_code, 1) << seconds << ":\n" << r.output;
    EXPECT_NE(r.output.find(message), std::string::npos) << r.output;
  }
}

}  // namespace
