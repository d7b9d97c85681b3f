// The camera network's security against peers that try to get in, over real TCP on 127.0.0.1: a
// node (NodeServer) publishing frames and a master (NodeSource) with their own keys, strangers with
// other keys or none, and a TCP proxy between master and node that records, injects and replays
// bytes on the wire.

#include <poll.h>
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <filesystem>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <zmq.hpp>

#include "tracking/camera/RigFile.h"
#include "tracking/net/CurveKeys.h"
#include "tracking/net/NodeServer.h"
#include "tracking/net/NodeSource.h"
#include "tracking/net/SocketSecurity.h"

namespace rhot {
namespace {

namespace fs = std::filesystem;

std::string on_loopback(int port) { return "tcp://127.0.0.1:" + std::to_string(port); }

// Key folders for a master, a node and a stranger of each kind, made fresh in a temporary folder:
// master/ trusts node0, node0/ trusts master; intruder/ (a master) trusts node0 but node0 does
// not trust it; impostor/ is a node key the master never heard of.
class KeyFolders {
 public:
  KeyFolders() : dir_(fs::temp_directory_path() / ("rhot-security-test-" + std::to_string(::getpid()))) {
    fs::remove_all(dir_);
    for (const char* name : {"master", "node0", "intruder", "impostor"}) {
      auto pair = make_key_pair(name);
      EXPECT_TRUE(pair && write_certificates((dir_ / name).string(), *pair)) << name;
      fs::create_directories(dir_ / name / "trusted");
    }
    trust("master", "node0");
    trust("node0", "master");
    trust("intruder", "node0");
    trust("impostor", "master");
  }
  ~KeyFolders() {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  NetSecurity ring(const std::string& name) const {
    auto r = load_key_ring((dir_ / name).string());
    EXPECT_TRUE(r.has_value()) << r.error();
    return r ? NetSecurity{*r} : NetSecurity{};
  }

 private:
  void trust(const std::string& who, const std::string& whom) {
    fs::copy_file(dir_ / whom / (whom + ".key"), dir_ / who / "trusted" / (whom + ".key"), fs::copy_options::overwrite_existing);
  }
  fs::path dir_;
};

// The node's one marker: every frame it sends has one detection here.
const Eigen::Vector2d kNodeMarker(640.0, 360.0);
// What an attacker would like the master to see.
const Eigen::Vector2d kFalseMarker(100.0, 100.0);

NodeFrameMessage frame_at(std::uint64_t counter, const Eigen::Vector2d& pixel) {
  NodeFrameMessage f;
  f.camera = 0;
  f.counter = counter;
  f.capture_ns = steady_now_ns();
  f.width = 1280;
  f.height = 720;
  f.detections.push_back({pixel, -1});
  return f;
}

// A node publishing one frame every 10 ms and answering requests, on its own thread.
class ServingNode {
 public:
  ServingNode(int port, const NetSecurity& security) {
    auto opened = NodeServer::open(on_loopback(port), on_loopback(port + 1), 0, 1, NodeClock{}, security);
    EXPECT_TRUE(opened.has_value()) << opened.error();
    if (!opened) return;
    server_ = std::move(*opened);
    thread_ = std::thread([this] {
      std::uint64_t counter = 0;
      while (!stop_) {
        std::lock_guard lock(mutex_);  // the server's stats are read from the test's thread
        server_->publish(frame_at(counter++, kNodeMarker));
        server_->serve_until(steady_now_ns() + 10'000'000);
        for (std::string& w : server_->take_warnings()) warnings_.push_back(std::move(w));
      }
    });
  }
  ~ServingNode() {
    stop_ = true;
    if (thread_.joinable()) thread_.join();
  }
  NodeServerStats stats() {
    std::lock_guard lock(mutex_);
    return server_->stats();
  }
  std::vector<std::string> warnings() {
    std::lock_guard lock(mutex_);
    return warnings_;
  }

 private:
  std::unique_ptr<NodeServer> server_;
  std::atomic<bool> stop_{false};
  std::mutex mutex_;
  std::vector<std::string> warnings_;
  std::thread thread_;
};

// What a master heard over `seconds`: frames with the node's camera, and every detection's pixel.
struct Heard {
  int frames = 0;
  std::vector<Eigen::Vector2d> pixels;
};
Heard hear(NodeSource& source, double seconds) {
  Heard h;
  const std::int64_t until = steady_now_ns() + static_cast<std::int64_t>(seconds * 1e9);
  while (steady_now_ns() < until) {
    for (const AssembledFrame& f : source.take_frames(0.02)) {
      if (!f.cameras[0]) continue;
      ++h.frames;
      for (const Detection& d : f.cameras[0]->detections) h.pixels.push_back(d.pixel);
    }
  }
  return h;
}

// Whether any warning contains `text`.
bool told(const std::vector<std::string>& warnings, const std::string& text) {
  return std::any_of(warnings.begin(), warnings.end(), [&](const std::string& w) { return w.find(text) != std::string::npos; });
}

CameraRig seated_rig() {
  auto rig = load_rig(std::filesystem::path(RHOT_ASSET_DIR) / "rigs" / "seated-4.yaml");
  EXPECT_TRUE(rig.has_value());
  return rig ? *rig : CameraRig{};
}

std::unique_ptr<NodeSource> open_master(const std::string& endpoint, const NetSecurity& security) {
  NodeSourceSettings settings;
  settings.security = security;
  auto source = NodeSource::open(seated_rig(), {endpoint}, settings);
  EXPECT_TRUE(source.has_value()) << source.error();
  return source ? std::move(*source) : nullptr;
}

TEST(NodeSecurity, AMasterHoldingTheNodesKeyAndTrustedByItGetsEveryFrame) {
  KeyFolders keys;
  const auto ports = free_tcp_port_pairs(1);
  ASSERT_TRUE(ports.has_value()) << ports.error();
  ServingNode node((*ports)[0], keys.ring("node0"));
  auto master = open_master("node0@" + on_loopback((*ports)[0]), keys.ring("master"));
  ASSERT_TRUE(master);
  const Heard h = hear(*master, 1.5);
  EXPECT_GT(h.frames, 50) << "a frame every 10 ms, once synchronised";
  for (const Eigen::Vector2d& p : h.pixels) EXPECT_EQ(p, kNodeMarker);
  const NodeStats s = master->stats().nodes[0];
  EXPECT_EQ(s.handshakes_failed, 0u);
  EXPECT_GE(s.handshake_ms, 0.0);
  EXPECT_LT(s.handshake_ms, 1000.0);
  EXPECT_GE(node.stats().masters_admitted, 2u) << "the master's frame and control sockets";
  EXPECT_EQ(node.stats().peers_refused, 0u);
}

TEST(NodeSecurity, AMasterTheNodeDoesNotTrustHearsNothingAndBothSidesSaySo) {
  KeyFolders keys;
  const auto ports = free_tcp_port_pairs(1);
  ASSERT_TRUE(ports.has_value()) << ports.error();
  ServingNode node((*ports)[0], keys.ring("node0"));
  auto intruder = open_master("node0@" + on_loopback((*ports)[0]), keys.ring("intruder"));
  ASSERT_TRUE(intruder);
  const Heard h = hear(*intruder, 1.5);
  EXPECT_EQ(h.frames, 0);
  EXPECT_GE(node.stats().peers_refused, 1u);
  EXPECT_TRUE(told(node.warnings(),
                   "which " + std::string(fs::temp_directory_path() / ("rhot-security-test-" + std::to_string(::getpid())) / "node0") +
                       "/trusted/ does not hold"))
      << "the node names the refused key and its folder";
  const NodeStats s = intruder->stats().nodes[0];
  EXPECT_GE(s.refused_by_node, 1u);
  EXPECT_TRUE(told(intruder->take_warnings(), "refused this master's key (status 400)"));
}

TEST(NodeSecurity, ANodeWithAnotherKeyIsNeverHeard) {
  KeyFolders keys;
  const auto ports = free_tcp_port_pairs(1);
  ASSERT_TRUE(ports.has_value()) << ports.error();
  // The impostor trusts the master and serves at node0's address, but holds another key.
  ServingNode impostor((*ports)[0], keys.ring("impostor"));
  auto master = open_master("node0@" + on_loopback((*ports)[0]), keys.ring("master"));
  ASSERT_TRUE(master);
  const Heard h = hear(*master, 1.5);
  EXPECT_EQ(h.frames, 0);
  EXPECT_GE(master->stats().nodes[0].handshakes_failed, 1u);
  EXPECT_TRUE(told(master->take_warnings(), "cannot prove it holds node0's secret key"));
  // A master without keys cannot talk to a node with them either.
  auto plain = open_master(on_loopback((*ports)[0]), NetSecurity{});
  ASSERT_TRUE(plain);
  EXPECT_EQ(hear(*plain, 0.5).frames, 0);
}

TEST(NodeSecurity, StrangersGetNothingAndTheNodeGoesOnServingItsMaster) {
  KeyFolders keys;
  const auto ports = free_tcp_port_pairs(1);
  ASSERT_TRUE(ports.has_value()) << ports.error();
  ServingNode node((*ports)[0], keys.ring("node0"));
  auto master = open_master("node0@" + on_loopback((*ports)[0]), keys.ring("master"));
  ASSERT_TRUE(master);
  // A plaintext subscriber, and a CURVE subscriber with a key the node does not list.
  zmq::context_t context;
  zmq::socket_t plain(context, zmq::socket_type::sub), curved(context, zmq::socket_type::sub);
  const NetSecurity stranger = keys.ring("intruder");
  for (zmq::socket_t* s : {&plain, &curved}) {
    s->set(zmq::sockopt::linger, 0);
    s->set(zmq::sockopt::subscribe, "");
    s->set(zmq::sockopt::rcvtimeo, 50);
  }
  ASSERT_EQ(zmq_setsockopt(curved.handle(), ZMQ_CURVE_SERVERKEY, keys.ring("master")->trusted_named("node0")->public_key.bytes.data(), 32),
            0);
  ASSERT_EQ(zmq_setsockopt(curved.handle(), ZMQ_CURVE_PUBLICKEY, stranger->own.public_key.bytes.data(), 32), 0);
  ASSERT_EQ(zmq_setsockopt(curved.handle(), ZMQ_CURVE_SECRETKEY, stranger->own.secret_key->bytes.data(), 32), 0);
  plain.connect(on_loopback((*ports)[0]));
  curved.connect(on_loopback((*ports)[0]));
  int stolen = 0;
  Heard heard;
  const std::int64_t until = steady_now_ns() + 1'500'000'000;
  while (steady_now_ns() < until) {
    zmq::message_t m;
    for (zmq::socket_t* s : {&plain, &curved})
      if (s->recv(m)) ++stolen;
    const Heard h = hear(*master, 0.02);
    heard.frames += h.frames;
  }
  EXPECT_EQ(stolen, 0) << "a subscriber the node does not trust reads nothing";
  EXPECT_GT(heard.frames, 50) << "and the node's own master is served all along";
  const NodeServerStats s = node.stats();
  EXPECT_GE(s.peers_refused, 1u) << "the CURVE stranger, refused by the node's ZAP handler";
  EXPECT_GE(s.handshakes_failed, 1u) << "the plaintext one, which cannot even begin the handshake";
  EXPECT_TRUE(told(node.warnings(), "failed the handshake"));
}

// A TCP proxy between a master and a node's frame socket, one connection at a time: it forwards
// both ways and records what the node sends; asked to, it injects bytes into the node's stream once,
// or answers a new connection with the recorded bytes instead of the node (a replay).
class Proxy {
 public:
  enum class Mode { kForward, kInjectOnce, kReplay };
  Proxy(int listen_port, int node_port) : node_port_(node_port) {
    listener_ = ::socket(AF_INET, SOCK_STREAM, 0);
    const int on = 1;
    ::setsockopt(listener_, SOL_SOCKET, SO_REUSEADDR, &on, sizeof on);
    sockaddr_in a = loopback(listen_port);
    EXPECT_EQ(::bind(listener_, reinterpret_cast<sockaddr*>(&a), sizeof a), 0);
    EXPECT_EQ(::listen(listener_, 4), 0);
    thread_ = std::thread([this] { run(); });
  }
  ~Proxy() {
    stop_ = true;
    thread_.join();
    ::close(listener_);
  }
  // A replay ends the connection in hand: the master's next one meets it.
  void set_mode(Mode m) {
    mode_ = m;
    if (m == Mode::kReplay) drop_ = true;
  }
  void set_injection(std::vector<std::uint8_t> bytes) {
    std::lock_guard lock(mutex_);
    injection_ = std::move(bytes);
  }
  std::vector<std::uint8_t> recorded() {
    std::lock_guard lock(mutex_);
    return recorded_;
  }
  int injected() const { return injected_; }

 private:
  static sockaddr_in loopback(int port) {
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    a.sin_port = htons(static_cast<std::uint16_t>(port));
    return a;
  }
  static bool send_all(int fd, const std::uint8_t* p, std::size_t n) {
    while (n > 0) {
      const ssize_t k = ::send(fd, p, n, MSG_NOSIGNAL);
      if (k <= 0) return false;
      p += k;
      n -= static_cast<std::size_t>(k);
    }
    return true;
  }
  void run() {
    while (!stop_) {
      pollfd l{listener_, POLLIN, 0};
      if (::poll(&l, 1, 20) <= 0) continue;
      const int client = ::accept(listener_, nullptr, nullptr);
      if (client < 0) continue;
      drop_ = false;
      if (mode_ == Mode::kReplay) {
        replay(client);
      } else {
        forward(client);
      }
      ::close(client);
    }
  }
  void replay(int client) {
    const std::vector<std::uint8_t> bytes = recorded();
    send_all(client, bytes.data(), bytes.size());
    std::uint8_t buf[4096];
    while (!stop_ && !drop_) {
      pollfd p{client, POLLIN, 0};
      if (::poll(&p, 1, 20) > 0 && ::recv(client, buf, sizeof buf, 0) <= 0) break;
    }
  }
  void forward(int client) {
    const int node = ::socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in a = loopback(node_port_);
    if (::connect(node, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) {
      ::close(node);
      return;
    }
    std::uint8_t buf[65536];
    std::size_t from_node = 0;
    while (!stop_ && !drop_) {
      pollfd p[2] = {{client, POLLIN, 0}, {node, POLLIN, 0}};
      if (::poll(p, 2, 20) <= 0) continue;
      if (p[0].revents) {
        const ssize_t n = ::recv(client, buf, sizeof buf, 0);
        if (n <= 0 || !send_all(node, buf, static_cast<std::size_t>(n))) break;
      }
      if (p[1].revents) {
        const ssize_t n = ::recv(node, buf, sizeof buf, 0);
        if (n <= 0) break;
        {
          std::lock_guard lock(mutex_);
          if (recorded_.size() < (1u << 20)) recorded_.insert(recorded_.end(), buf, buf + n);
        }
        from_node += static_cast<std::size_t>(n);
        // Well into the session (past the handshake), once: bytes of the attacker's own first.
        if (mode_ == Mode::kInjectOnce && from_node > 4096) {
          std::vector<std::uint8_t> junk;
          {
            std::lock_guard lock(mutex_);
            junk = injection_;
          }
          if (!send_all(client, junk.data(), junk.size())) break;
          ++injected_;
          mode_ = Mode::kForward;
        }
        if (!send_all(client, buf, static_cast<std::size_t>(n))) break;
      }
    }
    ::close(node);
  }

  int node_port_;
  int listener_ = -1;
  std::atomic<bool> stop_{false}, drop_{false};
  std::atomic<Mode> mode_{Mode::kForward};
  std::atomic<int> injected_{0};
  std::mutex mutex_;
  std::vector<std::uint8_t> recorded_, injection_;
  std::thread thread_;
};

// The bytes of one detection at `pixel` as a frame message carries it (its last 12 bytes).
std::vector<std::uint8_t> detection_bytes(const Eigen::Vector2d& pixel) {
  const std::vector<std::uint8_t> m = encode(frame_at(0, pixel));
  return {m.end() - 12, m.end()};
}

bool contains(const std::vector<std::uint8_t>& haystack, const std::vector<std::uint8_t>& needle) {
  return std::search(haystack.begin(), haystack.end(), needle.begin(), needle.end()) != haystack.end();
}

// A plaintext ZeroMQ message frame (ZMTP 3: flags, one-byte size, body) carrying a frame with the
// attacker's marker.
std::vector<std::uint8_t> plaintext_message() {
  const std::vector<std::uint8_t> body = encode(frame_at(1'000'000, kFalseMarker));
  std::vector<std::uint8_t> out{0x00, static_cast<std::uint8_t>(body.size())};
  out.insert(out.end(), body.begin(), body.end());
  return out;
}

TEST(NodeSecurity, OnTheWireFramesAreEncryptedAndInjectedOrReplayedBytesChangeNoMarker) {
  KeyFolders keys;
  const auto ports = free_tcp_port_pairs(2);
  ASSERT_TRUE(ports.has_value()) << ports.error();
  const int node_port = (*ports)[0], proxy_port = (*ports)[1];
  // Without security first: the same proxy sees the markers in the clear (what the check below
  // would find).
  {
    ServingNode node(node_port, NetSecurity{});
    Proxy frames(proxy_port, node_port), control(proxy_port + 1, node_port + 1);
    auto master = open_master(on_loopback(proxy_port), NetSecurity{});
    ASSERT_TRUE(master);
    EXPECT_GT(hear(*master, 1.0).frames, 20);
    EXPECT_TRUE(contains(frames.recorded(), detection_bytes(kNodeMarker))) << "in the clear without security";
  }
  ServingNode node(node_port, keys.ring("node0"));
  Proxy frames(proxy_port, node_port), control(proxy_port + 1, node_port + 1);
  frames.set_injection(plaintext_message());
  auto master = open_master("node0@" + on_loopback(proxy_port), keys.ring("master"));
  ASSERT_TRUE(master);
  Heard heard = hear(*master, 1.5);
  EXPECT_GT(heard.frames, 50);
  const std::vector<std::uint8_t> wire = frames.recorded();
  EXPECT_GT(wire.size(), 4096u);
  EXPECT_FALSE(contains(wire, detection_bytes(kNodeMarker))) << "encrypted on the wire";

  // The attacker's plaintext message pushed into the live stream: the master drops the connection
  // (the message is no CURVE box), connects again, and goes on with the node's frames.
  frames.set_mode(Proxy::Mode::kInjectOnce);
  const Heard after_injection = hear(*master, 3.0);
  EXPECT_EQ(frames.injected(), 1);
  EXPECT_GT(after_injection.frames, 30) << "the master reconnects through a fresh handshake";
  heard.pixels.insert(heard.pixels.end(), after_injection.pixels.begin(), after_injection.pixels.end());

  // A replay: what the node sent in an earlier session, played back to a new connection.
  const std::uint64_t failed_before = master->stats().nodes[0].handshakes_failed;
  frames.set_mode(Proxy::Mode::kReplay);
  const Heard in_flight = hear(*master, 0.2);  // what came before the switch, closed within its deadline
  heard.pixels.insert(heard.pixels.end(), in_flight.pixels.begin(), in_flight.pixels.end());
  const Heard replayed = hear(*master, 1.5);
  EXPECT_EQ(replayed.frames, 0) << "a recorded session is not a session";
  EXPECT_GT(master->stats().nodes[0].handshakes_failed, failed_before);
  for (const Eigen::Vector2d& p : heard.pixels) EXPECT_EQ(p, kNodeMarker) << "no marker but the node's was ever taken";
  EXPECT_EQ(master->stats().bad_messages, 0u) << "nothing the attacker sent reached the decoder";
}

// A trusted node that sends one message over the size limit: ZeroMQ ends that connection itself
// and would never reconnect it; the master opens the socket anew and hears the node again.
TEST(NodeSecurity, AfterAMessageOverTheSizeLimitTheNodeIsHeardAgain) {
  KeyFolders keys;
  const auto ports = free_tcp_port_pairs(1);
  ASSERT_TRUE(ports.has_value()) << ports.error();
  const NetSecurity node_keys = keys.ring("node0");
  zmq::context_t context;
  auto zap = ZapHandler::bind(context.handle(), *node_keys);
  ASSERT_TRUE(zap.has_value()) << zap.error();
  zmq::socket_t pub(context, zmq::socket_type::pub), rep(context, zmq::socket_type::rep);
  for (zmq::socket_t* s : {&pub, &rep}) {
    s->set(zmq::sockopt::linger, 0);
    ASSERT_TRUE(make_curve_server(s->handle(), *node_keys).has_value());
  }
  pub.bind(on_loopback((*ports)[0]));
  rep.bind(on_loopback((*ports)[0] + 1));
  std::atomic<bool> stop{false}, oversize{false};
  std::thread node([&] {
    std::uint64_t counter = 0;
    while (!stop) {
      (*zap)->answer();
      zmq::message_t request;
      while (rep.recv(request, zmq::recv_flags::dontwait)) {
        const auto d = decode(std::span(static_cast<const std::uint8_t*>(request.data()), request.size()));
        const TimeRequest q = d && std::holds_alternative<TimeRequest>(*d) ? std::get<TimeRequest>(*d) : TimeRequest{};
        (void)rep.send(zmq::buffer(encode(TimeReply{q.sequence, q.master_send_ns, steady_now_ns()})), zmq::send_flags::none);
      }
      if (oversize.exchange(false))
        (void)pub.send(zmq::buffer(std::vector<std::uint8_t>(kMaxNodeMessageBytes + 1000, 0x55)), zmq::send_flags::none);
      (void)pub.send(zmq::buffer(encode(frame_at(counter++, kNodeMarker))), zmq::send_flags::none);
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
  });
  auto master = open_master("node0@" + on_loopback((*ports)[0]), keys.ring("master"));
  ASSERT_TRUE(master);
  EXPECT_GT(hear(*master, 1.0).frames, 30);
  oversize = true;
  (void)hear(*master, 0.3);  // the frames before it, and the connection ends
  const Heard after = hear(*master, 2.5);
  stop = true;
  node.join();
  EXPECT_GT(after.frames, 50) << "heard again within about a second";
  EXPECT_EQ(master->stats().bad_messages, 0u) << "the message over the limit never reached the decoder";
}

TEST(NodeSecurity, ANodeListWithKeysNamesEachNodesCertificate) {
  KeyFolders keys;
  const CameraRig rig = seated_rig();
  NodeSourceSettings settings;
  settings.security = keys.ring("master");
  auto unnamed = NodeSource::open(rig, {"tcp://127.0.0.1:5601"}, settings);
  ASSERT_FALSE(unnamed.has_value());
  EXPECT_EQ(unnamed.error(),
            "node tcp://127.0.0.1:5601: with keys, name each node as NAME@tcp://127.0.0.1:5601, NAME.key being its certificate in " +
                settings.security->dir + "/trusted/");
  auto unknown = NodeSource::open(rig, {"node7@tcp://127.0.0.1:5601"}, settings);
  ASSERT_FALSE(unknown.has_value());
  EXPECT_EQ(unknown.error(), "node node7@tcp://127.0.0.1:5601: no " + settings.security->dir + "/trusted/node7.key (it holds node0)");
  EXPECT_EQ(parse_node_endpoints("a b@tcp://127.0.0.1:5601").error(),
            "node \"a b@tcp://127.0.0.1:5601\": key name \"a b\": only letters, digits, _ . and - (not ' ')");
  EXPECT_EQ(parse_node_endpoints("n0@tcp://127.0.0.1:5601,n1@tcp://127.0.0.1:5601").error(),
            "node endpoints \"n0@tcp://127.0.0.1:5601,n1@tcp://127.0.0.1:5601\": tcp://127.0.0.1:5601 twice");
}

}  // namespace
}  // namespace rhot
