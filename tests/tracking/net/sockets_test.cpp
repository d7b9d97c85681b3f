// The node's and the master's sockets against peers that misbehave, over real TCP on 127.0.0.1.

#include <atomic>
#include <chrono>
#include <thread>

#include <gtest/gtest.h>
#include <zmq.hpp>

#include "tracking/camera/RigFile.h"
#include "tracking/net/NodeServer.h"
#include "tracking/net/NodeSource.h"

namespace rhot {
namespace {

std::string tcp(int port) { return "tcp://127.0.0.1:" + std::to_string(port); }

std::vector<std::uint8_t> bytes_of(const zmq::message_t& m) {
  const auto* p = static_cast<const std::uint8_t*>(m.data());
  return {p, p + m.size()};
}

// One request through a DEALER (an empty delimiter frame, then the parts); the reply's payload.
std::optional<NodeMessage> ask(zmq::socket_t& dealer, const std::vector<std::vector<std::uint8_t>>& parts) {
  (void)dealer.send(zmq::message_t(), zmq::send_flags::sndmore);
  for (std::size_t i = 0; i < parts.size(); ++i)
    (void)dealer.send(zmq::buffer(parts[i]), i + 1 < parts.size() ? zmq::send_flags::sndmore : zmq::send_flags::none);
  zmq::message_t delimiter, reply;
  if (!dealer.recv(delimiter) || !dealer.recv(reply)) return std::nullopt;
  auto decoded = decode(bytes_of(reply));
  if (!decoded) return std::nullopt;
  return *decoded;
}

TEST(NodeServer, JunkRequestsAreAnsweredAsNotUnderstoodAndTheNodeGoesOn) {
  const auto ports = free_tcp_port_pairs(1);
  ASSERT_TRUE(ports.has_value()) << ports.error();
  NodeClock clock;
  clock.offset_ns = 5'000'000;  // the node's clock 5 ms ahead
  auto server = NodeServer::open(tcp((*ports)[0]), tcp((*ports)[0] + 1), 7, 1, clock, NetSecurity{});
  ASSERT_TRUE(server.has_value()) << server.error();
  std::atomic<bool> stop{false};
  std::thread serving([&] {
    while (!stop) (*server)->serve_until(steady_now_ns() + 5'000'000);
  });
  zmq::context_t context;
  zmq::socket_t dealer(context, zmq::socket_type::dealer);
  dealer.set(zmq::sockopt::rcvtimeo, 3000);
  dealer.set(zmq::sockopt::linger, 0);
  dealer.connect(tcp((*ports)[0] + 1));

  const auto junk = ask(dealer, {{'h', 'e', 'l', 'l', 'o'}});
  ASSERT_TRUE(junk.has_value());
  EXPECT_EQ(std::get<StatusReply>(*junk).sequence, 0u) << "an empty status reply: not understood";
  const auto multipart = ask(dealer, {encode(TimeRequest{1, 2}), {'x'}});
  ASSERT_TRUE(multipart.has_value());
  EXPECT_TRUE(std::holds_alternative<StatusReply>(*multipart)) << "a request in two parts is not a request";
  // And it still tells the time.
  const std::int64_t before = steady_now_ns();
  const auto time = ask(dealer, {encode(TimeRequest{3, before})});
  const std::int64_t after = steady_now_ns();
  ASSERT_TRUE(time.has_value());
  const auto& t = std::get<TimeReply>(*time);
  EXPECT_EQ(t.sequence, 3u);
  EXPECT_EQ(t.master_send_ns, before);
  EXPECT_GE(t.node_ns, before + 5'000'000);
  EXPECT_LE(t.node_ns, after + 5'000'000);
  const auto status = ask(dealer, {encode(StatusRequest{9})});
  ASSERT_TRUE(status.has_value());
  EXPECT_EQ(std::get<StatusReply>(*status).node, 7);
  stop = true;
  serving.join();
  EXPECT_EQ((*server)->stats().bad_requests, 2u);
}

TEST(NodeSource, APublisherSendingJunkIsCountedAndItsGoodFramesStillTracked) {
  // A "node" made by hand: frames on a PUB socket, interleaved with junk, and time replies from a
  // REP socket beside it. The master counts and tells the junk and assembles the frames.
  const auto ports = free_tcp_port_pairs(1);
  ASSERT_TRUE(ports.has_value()) << ports.error();
  auto rig = load_rig(std::string(RHOT_ASSET_DIR) + "/rigs/seated-4.yaml");
  ASSERT_TRUE(rig.has_value());
  zmq::context_t context;
  zmq::socket_t pub(context, zmq::socket_type::pub), rep(context, zmq::socket_type::rep);
  pub.set(zmq::sockopt::linger, 0);
  rep.set(zmq::sockopt::linger, 0);
  pub.bind(tcp((*ports)[0]));
  rep.bind(tcp((*ports)[0] + 1));
  auto source = NodeSource::open(*rig, {tcp((*ports)[0])});
  ASSERT_TRUE(source.has_value()) << source.error();
  std::uint64_t counter = 0;
  std::size_t frames = 0;
  std::vector<std::string> warnings;
  const std::int64_t give_up = steady_now_ns() + 10'000'000'000;
  while (frames < 20 && steady_now_ns() < give_up) {
    zmq::message_t request;
    while (rep.recv(request, zmq::recv_flags::dontwait)) {
      const auto r = decode(bytes_of(request));
      const TimeRequest q = r && std::holds_alternative<TimeRequest>(*r) ? std::get<TimeRequest>(*r) : TimeRequest{};
      (void)rep.send(zmq::buffer(encode(TimeReply{q.sequence, q.master_send_ns, steady_now_ns()})), zmq::send_flags::none);
    }
    NodeFrameMessage f;
    f.camera = 0;
    f.counter = counter++;
    f.capture_ns = steady_now_ns();
    f.width = 1280;
    f.height = 720;
    f.detections.push_back({Eigen::Vector2d(640.0, 360.0), -1});
    (void)pub.send(zmq::buffer(std::string("junk")), zmq::send_flags::none);
    auto truncated = encode(f);
    truncated.resize(truncated.size() - 3);
    (void)pub.send(zmq::buffer(truncated), zmq::send_flags::none);
    (void)pub.send(zmq::buffer(encode(f)), zmq::send_flags::none);
    for (const AssembledFrame& a : (*source)->take_frames(0.01)) {
      if (a.cameras[0]) ++frames;
      EXPECT_EQ(a.cameras_present(), 1);
      // The tracker is told which cameras sent nothing (the overlay shows them).
      const RigFrame r = (*source)->to_rig_frame(a);
      EXPECT_TRUE(r.cameras[0].delivered);
      EXPECT_FALSE(r.cameras[1].delivered);
    }
    for (auto& w : (*source)->take_warnings()) warnings.push_back(w);
  }
  EXPECT_GE(frames, 20u);
  const NodeSourceStats stats = (*source)->stats();
  EXPECT_GE(stats.bad_messages, 20u);
  const auto told = [&](const std::string& text) {
    return std::any_of(warnings.begin(), warnings.end(), [&](const std::string& w) { return w.find(text) != std::string::npos; });
  };
  EXPECT_TRUE(told("bad message (not a rhot node message, 1 so far): not a rhot node message (no 'RN' header)"));
  EXPECT_TRUE(told("bad message (truncated, 1 so far): frame: 1 detections need 42 bytes after the header, got 39"));
  EXPECT_FALSE(told("(truncated, 2 so far)")) << "told at the 1st, 10th, 100th ..., not every time";
}

}  // namespace
}  // namespace rhot
