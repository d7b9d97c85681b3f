// The OSC stream over real UDP on loopback: liblo's own server and Debian's oscdump receive what
// OscStream sends, and the bones are checked against the skeleton that was sent.

#include "engine/stream/OscStream.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <lo/lo.h>
#include <map>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "tests/support/OscReceiver.h"
#include "tracking/hand/JointFrames.h"

namespace rhot {
namespace {

using namespace std::chrono_literals;

// A UDP port nothing listens on now (the kernel's pick, released).
int free_udp_port() {
  const int fd = socket(AF_INET, SOCK_DGRAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a);
  socklen_t n = sizeof a;
  getsockname(fd, reinterpret_cast<sockaddr*>(&a), &n);
  close(fd);
  return ntohs(a.sin_port);
}

// Whether a UDP port on loopback is taken (somebody bound it).
bool udp_port_taken(int port) {
  const int fd = socket(AF_INET, SOCK_DGRAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_ANY);
  a.sin_port = htons(static_cast<std::uint16_t>(port));
  const bool taken = bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0;
  close(fd);
  return taken;
}

// The reference hand turned and placed in the world, each finger curled at its three hinges by
// `curl` radians (about the hand's X axis, so every bone keeps its length).
HandInput curled_hand(HandSide side, double curl, const Eigen::Vector3d& at) {
  HandPose pose = reference_open_hand(side);
  for (int finger = 0; finger < 4; ++finger) {
    const int base = 7 + 5 * finger;  // proximal
    for (int hinge = 0; hinge < 3; ++hinge) {
      const Eigen::Vector3d pivot = pose.position_m[static_cast<std::size_t>(base + hinge)];
      const Eigen::AngleAxisd turn(curl * (1.0 + 0.2 * hinge), Eigen::Vector3d::UnitX());
      for (int j = base + hinge + 1; j <= base + 3; ++j) {
        auto& p = pose.position_m[static_cast<std::size_t>(j)];
        p = pivot + turn * (p - pivot);
      }
    }
  }
  Rigid3d world_from_hand;
  world_from_hand.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(0.4, Eigen::Vector3d(0.3, 1.0, -0.2).normalized()));
  world_from_hand.translation = at;
  return hand_input(world_from_hand, pose);
}

TrackingResults two_hands(double t_s) {
  TrackingResults r;
  r.t_s = t_s;
  r.hands[0] = curled_hand(HandSide::kLeft, 0.3, {-0.2, 1.0, -0.3});
  r.hands[1] = curled_hand(HandSide::kRight, 0.6, {0.25, 1.1, -0.35});
  Rigid3d mug;
  mug.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitY()));
  mug.translation = {0.1, 0.8, -0.5};
  r.world_from_object[3] = mug;
  return r;
}

using Received = rhot::test::OscReceived;
using Receiver = rhot::test::OscReceiver;

Eigen::Vector3d position_of(const Received& m) { return {m.numbers[0], m.numbers[1], m.numbers[2]}; }
Eigen::Quaterniond rotation_of(const Received& m) { return Eigen::Quaterniond(m.numbers[6], m.numbers[3], m.numbers[4], m.numbers[5]); }

std::unique_ptr<OscStream> stream_to(int port, bool vmc) {
  auto s = OscStream::open({"127.0.0.1", std::to_string(port), vmc});
  EXPECT_TRUE(s.has_value()) << s.error();
  return s ? std::move(*s) : nullptr;
}

TEST(OscStream, UrlsAreReadAndBadOnesNamed) {
  const auto plain = parse_stream_url("osc://localhost:9000");
  ASSERT_TRUE(plain.has_value()) << plain.error();
  EXPECT_EQ(plain->host, "localhost");
  EXPECT_EQ(plain->port, "9000");
  EXPECT_FALSE(plain->vmc);
  const auto vmc = parse_stream_url("osc://127.0.0.1:39539,vmc");
  ASSERT_TRUE(vmc.has_value()) << vmc.error();
  EXPECT_EQ(vmc->host, "127.0.0.1");
  EXPECT_EQ(vmc->port, "39539");
  EXPECT_TRUE(vmc->vmc);
  EXPECT_EQ(parse_stream_url("udp://localhost:9000").error(),
            "--stream: expected osc://HOST:PORT or osc://HOST:PORT,vmc, got \"udp://localhost:9000\"");
  EXPECT_EQ(parse_stream_url("osc://localhost").error(),
            "--stream: expected osc://HOST:PORT or osc://HOST:PORT,vmc, got \"osc://localhost\"");
  EXPECT_EQ(parse_stream_url("osc://localhost:0").error(),
            "--stream: the port must be a number from 1 to 65535, got \"osc://localhost:0\"");
  EXPECT_EQ(parse_stream_url("osc://localhost:70000").error(),
            "--stream: the port must be a number from 1 to 65535, got \"osc://localhost:70000\"");
  EXPECT_EQ(parse_stream_url("osc://h:9x").error(), "--stream: the port must be a number from 1 to 65535, got \"osc://h:9x\"");
  EXPECT_EQ(parse_stream_url("osc://h:9000,vnc").error(),
            "--stream: unknown option \"vnc\" (the one option is vmc), got \"osc://h:9000,vnc\"");
  EXPECT_EQ(
      parse_stream_url("osc://[::1]:9000").error(),
      "--stream: IPv6 addresses are not supported (liblo sends over IPv4): give an IPv4 address or a host name, got \"osc://[::1]:9000\"");
  EXPECT_EQ(OscStream::open({"no-such-host.invalid", "9000", false})
                .error()
                .rfind("--stream: host \"no-such-host.invalid\" does not resolve: ", 0),
            0u);
}

TEST(OscStream, VmcMapsEveryHumanoidHandBoneOnce) {
  std::vector<std::string> names;
  for (const HandJoint j : vmc_hand_joints()) names.push_back(vmc_bone_name(HandSide::kRight, j));
  const std::vector<std::string> expected{"RightHand",         "RightThumbProximal",  "RightThumbIntermediate",
                                          "RightThumbDistal",  "RightIndexProximal",  "RightIndexIntermediate",
                                          "RightIndexDistal",  "RightMiddleProximal", "RightMiddleIntermediate",
                                          "RightMiddleDistal", "RightRingProximal",   "RightRingIntermediate",
                                          "RightRingDistal",   "RightLittleProximal", "RightLittleIntermediate",
                                          "RightLittleDistal"};
  EXPECT_EQ(names, expected);
  EXPECT_EQ(vmc_bone_name(HandSide::kLeft, HandJoint::kIndexMetacarpal), "");
  EXPECT_EQ(vmc_bone_name(HandSide::kLeft, HandJoint::kPalm), "");
  EXPECT_EQ(vmc_bone_name(HandSide::kLeft, HandJoint::kLittleTip), "");
  EXPECT_EQ(vmc_bone_name(HandSide::kLeft, HandJoint::kThumbMetacarpal), "LeftThumbProximal");
}

// VMC over loopback to liblo's server: the frame's messages in order, bone names for both hands,
// and the bones put back together (local positions and rotations chained from the wrist, Unity's
// frame turned back into rhot's) land on the joints sent, in metres, to float precision.
TEST(OscStream, VmcBonesRebuildTheSkeletonSent) {
  Receiver receiver;
  const auto stream = stream_to(receiver.port(), true);
  ASSERT_TRUE(stream);
  const TrackingResults results = two_hands(1.25);
  stream->send(results, {{3, "mug"}});
  stream->flush();
  const std::size_t expected_count = 4 + 2 * 16 + 1;
  const std::vector<Received>& got = receiver.receive(expected_count);
  ASSERT_EQ(got.size(), expected_count);
  EXPECT_EQ(got[0].path, "/rhot/frame");
  EXPECT_EQ(got[0].types, "if");
  EXPECT_EQ(got[0].numbers, (std::vector<double>{0.0, 1.25}));
  EXPECT_EQ(got[1].path, "/VMC/Ext/OK");
  EXPECT_EQ(got[2].path, "/VMC/Ext/T");
  EXPECT_EQ(got[3].path, "/VMC/Ext/Root/Pos");

  const auto from_unity_p = [](const Eigen::Vector3d& p) { return Eigen::Vector3d(p.x(), p.y(), -p.z()); };
  const auto from_unity_q = [](const Eigen::Quaterniond& q) { return Eigen::Quaterniond(q.w(), -q.x(), -q.y(), q.z()); };
  for (int h = 0; h < 2; ++h) {
    const HandSide side = h == 0 ? HandSide::kLeft : HandSide::kRight;
    const HandInput& hand = results.hands[static_cast<std::size_t>(h)];
    std::map<HandJoint, Eigen::Vector3d> position;    // rhot's world
    std::map<HandJoint, Eigen::Quaterniond> rotated;  // from the T-pose, rhot's world
    for (std::size_t b = 0; b < 16; ++b) {
      const Received& m = got[4 + 16 * static_cast<std::size_t>(h) + b];
      const HandJoint joint = vmc_hand_joints()[b];
      ASSERT_EQ(m.path, "/VMC/Ext/Bone/Pos");
      ASSERT_EQ(m.types, "sfffffff");
      ASSERT_EQ(m.strings[0], vmc_bone_name(side, joint));
      const Eigen::Vector3d p = from_unity_p(position_of(m));
      const Eigen::Quaterniond q = from_unity_q(rotation_of(m));
      EXPECT_NEAR(q.norm(), 1.0, 1e-6);
      if (joint == HandJoint::kWrist) {
        position[joint] = p;
        rotated[joint] = q;
      } else {
        const HandJoint parent = (b == 1 || b % 3 == 1) ? HandJoint::kWrist : vmc_hand_joints()[b - 1];
        position[joint] = position.at(parent) + rotated.at(parent) * p;
        rotated[joint] = rotated.at(parent) * q;
        // Units: a bone's local offset is its length in metres.
        EXPECT_NEAR(p.norm(),
                    (hand.joints_world[static_cast<std::size_t>(joint)] - hand.joints_world[static_cast<std::size_t>(parent)]).norm(),
                    1e-6);
      }
      EXPECT_LT((position[joint] - hand.joints_world[static_cast<std::size_t>(joint)]).norm(), 2e-6) << m.strings[0];
    }
    // The last bone of each finger points at its tip: in the T-pose bones run along -X (left) or
    // +X (right).
    const Eigen::Vector3d rest_along(side == HandSide::kLeft ? -1.0 : 1.0, 0.0, 0.0);
    for (const auto& [distal, tip] :
         {std::pair{HandJoint::kIndexDistal, HandJoint::kIndexTip}, std::pair{HandJoint::kLittleDistal, HandJoint::kLittleTip},
          std::pair{HandJoint::kThumbDistal, HandJoint::kThumbTip}}) {
      const Eigen::Vector3d along =
          (hand.joints_world[static_cast<std::size_t>(tip)] - hand.joints_world[static_cast<std::size_t>(distal)]).normalized();
      EXPECT_LT((rotated.at(distal) * rest_along - along).norm(), 1e-5);
    }
  }
  const Received& mug = got.back();
  EXPECT_EQ(mug.path, "/VMC/Ext/Tra/Pos");
  EXPECT_EQ(mug.strings[0], "mug");
  EXPECT_LT((position_of(mug) - Eigen::Vector3d(0.1, 0.8, 0.5)).norm(), 1e-6);
  // In Unity's frame the sent rotation turns a vector as the object turns it in rhot's: for v in
  // Unity's frame, q_sent v = S R S v with S the flip of Z.
  const Eigen::Matrix3d flip = Eigen::Vector3d(1, 1, -1).asDiagonal();
  const Eigen::Vector3d v(0.3, -0.2, 0.9);
  const Eigen::Vector3d expected_v = flip * (results.world_from_object.at(3).rotation * (flip * v));
  EXPECT_LT((rotation_of(mug).normalized() * v - expected_v).norm(), 1e-6);
}

// rhot's own address space: the 26 joints in OpenXR's order with names, positions in rhot's
// frame, orientations whose -Z runs along the bone; a hand not seen is announced and left out.
TEST(OscStream, RhotAddressesCarryTheOpenXrJoints) {
  Receiver receiver;
  const auto stream = stream_to(receiver.port(), false);
  ASSERT_TRUE(stream);
  TrackingResults results = two_hands(0.5);
  results.hands[1].seen = false;
  Rigid3d broken;
  broken.translation = {std::nan(""), 0.0, 0.0};
  results.world_from_object[7] = broken;  // a pose that is not finite is never sent
  stream->send(results, {});
  stream->flush();
  const std::vector<Received>& got = receiver.receive(1 + 1 + 26 + 1 + 1);
  ASSERT_EQ(got.size(), 30u);
  EXPECT_EQ(got[1].path, "/rhot/hand");
  EXPECT_EQ(got[1].strings[0], "left");
  EXPECT_EQ(got[1].numbers[0], 1.0);
  const HandInput& left = results.hands[0];
  for (int j = 0; j < kHandJointCount; ++j) {
    const Received& m = got[2 + static_cast<std::size_t>(j)];
    ASSERT_EQ(m.path, "/rhot/hand/joint");
    EXPECT_EQ(m.strings, (std::vector<std::string>{"left", std::string(joint_name(static_cast<HandJoint>(j)))}));
    EXPECT_LT((position_of(m) - left.joints_world[static_cast<std::size_t>(j)]).norm(), 1e-6);
    if (const auto child = joint_child(static_cast<HandJoint>(j))) {
      const Eigen::Vector3d along =
          (left.joints_world[static_cast<std::size_t>(*child)] - left.joints_world[static_cast<std::size_t>(j)]).normalized();
      EXPECT_LT((rotation_of(m).normalized() * -Eigen::Vector3d::UnitZ() - along).norm(), 1e-5) << joint_name(static_cast<HandJoint>(j));
    }
  }
  EXPECT_EQ(got[28].path, "/rhot/hand");
  EXPECT_EQ(got[28].strings[0], "right");
  EXPECT_EQ(got[28].numbers[0], 0.0);
  EXPECT_EQ(got[29].path, "/rhot/body");
  EXPECT_EQ(got[29].strings[0], "star-3");
}

// Nobody listening, then a receiver that comes and goes: every frame is accounted for (sent,
// failed or skipped), and every frame handed over while the receiver is there arrives.
TEST(OscStream, AReceiverThatIsNotThereOrGoesAwayIsHarmless) {
  const int port = free_udp_port();
  const auto stream = stream_to(port, true);
  ASSERT_TRUE(stream);
  const TrackingResults results = two_hands(0.0);
  for (int f = 0; f < 20; ++f) {
    stream->send(results, {});
    std::this_thread::sleep_for(1ms);
  }
  stream->flush();
  {
    lo_server server = lo_server_new_with_proto(std::to_string(port).c_str(), LO_UDP, nullptr);
    ASSERT_NE(server, nullptr);
    int frames = 0;
    lo_server_add_method(
        server, "/rhot/frame", "if",
        [](const char*, const char*, lo_arg**, int, lo_message, void* n) { return ++*static_cast<int*>(n), 0; }, &frames);
    for (int f = 0; f < 5; ++f) {
      stream->send(results, {});
      stream->flush();
      while (lo_server_recv_noblock(server, 200) > 0) {
      }
    }
    EXPECT_EQ(frames, 5);
    lo_server_free(server);
  }
  for (int f = 0; f < 20; ++f) stream->send(results, {});
  stream->flush();
  const OscStream::Stats s = stream->stats();
  EXPECT_EQ(s.given, 45u);
  EXPECT_EQ(s.sent + s.skipped + s.errors, 45u);
  EXPECT_GE(s.sent, 5u);
}

// Debian's oscdump (liblo-tools) as an independent receiver: every frame arrives with its counter,
// and the joints it prints are the ones sent.
TEST(OscStream, OscdumpReceivesEveryFrame) {
  const int port = free_udp_port();
  const std::filesystem::path dir = std::filesystem::path(::testing::TempDir()) / "rhot_oscdump";
  std::filesystem::create_directories(dir);
  const std::filesystem::path out = dir / "dump.txt", pid = dir / "pid";
  const std::string command = "oscdump -L " + std::to_string(port) + " > " + out.string() + " 2>&1 & echo $! > " + pid.string();
  ASSERT_EQ(std::system(command.c_str()), 0);
  // A loaded two-core CI machine once took over 2 s to start it: wait up to 15 s, and say what it
  // printed if it never bound the port.
  for (int wait = 0; wait < 1500 && !udp_port_taken(port); ++wait) std::this_thread::sleep_for(10ms);
  if (!udp_port_taken(port)) {
    std::system(("kill $(cat " + pid.string() + ") 2>/dev/null").c_str());
    std::ifstream printed(out);
    const std::string said((std::istreambuf_iterator<char>(printed)), std::istreambuf_iterator<char>());
    FAIL() << "oscdump did not bind port " << port << " within 15 s (is liblo-tools installed? tools/setup-deps.sh); it printed: \"" << said
           << "\"";
  }
  const auto stream = stream_to(port, false);
  ASSERT_TRUE(stream);
  const TrackingResults results = two_hands(2.0);
  for (int f = 0; f < 10; ++f) {
    stream->send(results, {{3, "mug"}});
    stream->flush();
    std::this_thread::sleep_for(2ms);
  }
  // Until it has printed the tenth frame's last message (each frame's bundle ends with the body), or
  // 10 s: a loaded machine may be slow to schedule it.
  const auto bodies_printed = [&] {
    std::ifstream printed(out);
    int n = 0;
    for (std::string line; std::getline(printed, line);) n += line.find("/rhot/body") != std::string::npos ? 1 : 0;
    return n;
  };
  for (int wait = 0; wait < 1000 && bodies_printed() < 10; ++wait) std::this_thread::sleep_for(10ms);
  std::system(("kill $(cat " + pid.string() + ")").c_str());
  std::ifstream in(out);
  std::string line;
  std::vector<int> frames;
  int joints = 0;
  while (std::getline(in, line)) {
    std::istringstream words(line);
    std::string stamp, path, types;
    words >> stamp >> path >> types;
    if (path == "/rhot/frame") {
      int frame = -1;
      words >> frame;
      frames.push_back(frame);
    } else if (path == "/rhot/hand/joint") {
      EXPECT_EQ(types, "ssfffffff");
      std::string side, name;
      double x = 0, y = 0, z = 0;
      words >> side >> name >> x >> y >> z;
      if (side == "\"right\"" && name == "\"index_tip\"") {
        const Eigen::Vector3d& tip = results.hands[1].joints_world[static_cast<std::size_t>(HandJoint::kIndexTip)];
        EXPECT_LT((Eigen::Vector3d(x, y, z) - tip).norm(), 2e-6);  // oscdump prints six decimals
      }
      ++joints;
    }
  }
  EXPECT_EQ(frames, (std::vector<int>{0, 1, 2, 3, 4, 5, 6, 7, 8, 9}));
  EXPECT_EQ(joints, 10 * 2 * kHandJointCount);
}

}  // namespace
}  // namespace rhot
