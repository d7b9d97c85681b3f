#include "tracking/net/NodeSource.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <charconv>
#include <chrono>
#include <condition_variable>
#include <limits>
#include <mutex>
#include <cstdio>
#include <thread>
#include <utility>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>
#include <zmq.hpp>

#include "tracking/net/ClockSync.h"
#include "tracking/net/NodeProtocol.h"
#include "tracking/net/SocketSecurity.h"

namespace rhot {

std::int64_t steady_now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

std::expected<void, std::string> check_endpoint(const std::string& endpoint, bool allow_wildcard) {
  const auto bad = [&](const std::string& why) { return std::unexpected("endpoint \"" + endpoint + "\": " + why); };
  if (endpoint.rfind("ipc://", 0) == 0) return endpoint.size() > 6 ? std::expected<void, std::string>{} : bad("no path after ipc://");
  if (endpoint.rfind("inproc://", 0) == 0) return endpoint.size() > 9 ? std::expected<void, std::string>{} : bad("no name after inproc://");
  if (endpoint.rfind("tcp://", 0) != 0) return bad("expected tcp://HOST:PORT, ipc://PATH or inproc://NAME");
  const std::string rest = endpoint.substr(6);
  const auto colon = rest.rfind(':');
  if (colon == std::string::npos || colon == 0) return bad("expected tcp://HOST:PORT");
  const std::string host = rest.substr(0, colon), port_text = rest.substr(colon + 1);
  int port = 0;
  const auto [end, ec] = std::from_chars(port_text.data(), port_text.data() + port_text.size(), port);
  if (ec != std::errc() || end != port_text.data() + port_text.size() || port < 1 || port > 65534)
    return bad("port \"" + port_text + "\" is not a number from 1 to 65534 (the control endpoint is the port + 1)");
  if (host == "*" && !allow_wildcard) return bad("\"*\" would listen on every network; name the address to use");
  if (host.find_first_of(" /\\") != std::string::npos) return bad("host \"" + host + "\" is not an address or a name");
  return {};
}

std::string control_endpoint_for(const std::string& publish) {
  if (publish.rfind("tcp://", 0) == 0) {
    const auto colon = publish.rfind(':');
    int port = 0;
    std::from_chars(publish.data() + colon + 1, publish.data() + publish.size(), port);
    return publish.substr(0, colon + 1) + std::to_string(port + 1);
  }
  return publish + ".control";
}

std::expected<NodeAddress, std::string> parse_node_address(const std::string& item) {
  NodeAddress out;
  out.endpoint = item;
  const auto at = item.find('@');
  if (at != std::string::npos && item.find("://") > at) {
    out.name = item.substr(0, at);
    out.endpoint = item.substr(at + 1);
    if (auto ok = check_key_name(out.name); !ok) return std::unexpected("node \"" + item + "\": " + ok.error());
  }
  if (auto ok = check_endpoint(out.endpoint); !ok) return std::unexpected(ok.error());
  return out;
}

std::expected<std::vector<std::string>, std::string> parse_node_endpoints(const std::string& list) {
  std::vector<std::string> out;
  std::size_t start = 0;
  while (start <= list.size()) {
    const auto comma = list.find(',', start);
    const std::string item = list.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    if (item.empty()) return std::unexpected("node endpoints \"" + list + "\": an empty entry");
    const auto address = parse_node_address(item);
    if (!address) return std::unexpected(address.error());
    for (const std::string& earlier : out)
      if (parse_node_address(earlier)->endpoint == address->endpoint)
        return std::unexpected("node endpoints \"" + list + "\": " + address->endpoint + " twice");
    out.push_back(item);
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return out;
}

std::expected<std::vector<int>, std::string> free_tcp_port_pairs(int count) {
  const auto bind_loopback = [](int port) -> int {
    const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
    if (fd < 0) return -1;
    sockaddr_in addr{};
    addr.sin_family = AF_INET;
    addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    addr.sin_port = htons(static_cast<std::uint16_t>(port));
    if (::bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0) {
      ::close(fd);
      return -1;
    }
    return fd;
  };
  std::vector<int> held, out;
  for (int attempt = 0; attempt < 64 * count + 64 && static_cast<int>(out.size()) < count; ++attempt) {
    const int fd = bind_loopback(0);
    if (fd < 0) break;
    sockaddr_in addr{};
    socklen_t len = sizeof addr;
    ::getsockname(fd, reinterpret_cast<sockaddr*>(&addr), &len);
    const int port = ntohs(addr.sin_port);
    held.push_back(fd);
    if (port >= 65535) continue;
    const int next = bind_loopback(port + 1);
    if (next < 0) continue;
    held.push_back(next);
    out.push_back(port);
  }
  for (const int fd : held) ::close(fd);
  if (static_cast<int>(out.size()) < count)
    return std::unexpected("cannot find " + std::to_string(count) + " free pairs of loopback ports");
  return out;
}

struct NodeSource::Impl {
  struct Node {
    std::string endpoint;
    zmq::socket_t frames;
    zmq::socket_t control;
    ClockSync clock;
    NodeStats stats;
    std::int64_t last_frame_ns = 0;
    std::int64_t next_sync_ns = 0;
    std::int64_t next_status_ns = 0;
    std::int64_t first_sync_ns = 0;
    // The fastest round trip of its time requests ever (kept when its clock is measured anew: the
    // path to it is the same): what a round trip to it can be.
    std::int64_t fastest_rtt_ns = std::numeric_limits<std::int64_t>::max();
    bool placing = false;               // its frames are placed in time (since its clock was last measured anew)
    std::int64_t first_sample_ns = 0;   // the first clock sample since then (master clock)
    std::int64_t measured_from_ns = 0;  // replies to requests sent before this (an earlier clock) are not samples
    std::uint32_t sequence = 0;
    std::optional<std::uint64_t> last_counter{};  // of its last frame
    std::string node_name{};                      // its certificate's, with security
    std::string address{};                        // the endpoint without the name
    std::optional<CurveKey> node_key{};
    // Each socket's connections and handshakes; a socket whose session ZeroMQ ended (a bad key,
    // injected or replayed bytes, a message over the size limit: ZeroMQ does not reconnect those)
    // is opened anew at its reopen time (0: not due).
    std::unique_ptr<HandshakeMonitor> frames_monitor{}, control_monitor{};
    std::int64_t reopen_frames_ns = 0, reopen_control_ns = 0;
    std::int64_t connected_ns = 0;  // the latest TCP connection, for the handshake's time
  };

  // How long after a protocol error a node's socket is opened anew: a peer that keeps failing the
  // handshake is retried twice a second, not in a busy loop.
  static constexpr std::int64_t kReopenAfter_ns = 500'000'000;
  static constexpr std::int64_t kReconnectWait_ns = 1'000'000'000;

  CameraRig rig;
  NodeSourceSettings settings;
  std::int64_t opened_ns = steady_now_ns();
  std::int64_t origin_ns;
  zmq::context_t context{1};
  std::vector<Node> nodes;

  mutable std::mutex mutex;  // guards everything below, and nodes' stats and clocks for readers
  std::condition_variable arrived;
  FrameAssembler assembler;
  std::vector<std::int64_t> camera_last_ns;  // per rig camera: its latest frame's arrival (0: never)
  std::uint64_t superseded = 0;
  std::uint64_t bad_messages = 0;
  std::array<std::uint64_t, kNodeDecodeErrorKinds> bad_by_kind{};
  std::vector<std::string> warnings;
  std::uint64_t frame_index = 0;

  std::atomic<bool> stop{false};
  std::atomic<std::int64_t> stall_ns{0};  // stall_receiver's, taken by the thread's next turn
  std::thread receiver;

  Impl(const CameraRig& r, NodeSourceSettings s)
      : rig(r),
        settings(s),
        origin_ns(s.time_origin_ns.value_or(opened_ns)),
        assembler(static_cast<int>(r.cameras.size()), s.assembly),
        camera_last_ns(r.cameras.size(), 0) {}

  void warn(std::string line) {
    if (warnings.size() < 1000) warnings.push_back(std::move(line));
  }

  void on_frame(Node& node, const zmq::message_t& raw, std::int64_t arrival_ns) {
    const auto bytes = std::span(static_cast<const std::uint8_t*>(raw.data()), raw.size());
    auto decoded = decode(bytes);
    std::lock_guard lock(mutex);
    node.stats.bytes += raw.size();
    if (!decoded || !std::holds_alternative<NodeFrameMessage>(*decoded)) {
      const NodeDecodeFailure failure =
          decoded ? NodeDecodeFailure{NodeDecodeError::kUnknownType, "a request or reply on the frame socket"} : decoded.error();
      ++bad_messages;
      if (worth_telling(++bad_by_kind[static_cast<std::size_t>(failure.kind)]))
        warn("node " + node.endpoint + ": bad message (" + to_string(failure.kind) + ", " +
             std::to_string(bad_by_kind[static_cast<std::size_t>(failure.kind)]) + " so far): " + failure.message);
      return;
    }
    NodeFrameMessage& m = std::get<NodeFrameMessage>(*decoded);
    if (m.camera >= rig.cameras.size()) {
      ++bad_messages;
      if (worth_telling(++bad_by_kind[static_cast<std::size_t>(NodeDecodeError::kBadValue)]))
        warn("node " + node.endpoint + ": camera " + std::to_string(m.camera) + " is not in the rig (" +
             std::to_string(rig.cameras.size()) + " cameras)");
      return;
    }
    // A counter lower than the last one heard: the node started again, with a clock that may be
    // another (a restarted machine, or one that ran with another offset): measured anew before
    // its frames are placed in time. Within lost_after_s of its last frame it was never lost, so
    // this is the only sign of it.
    if (node.last_counter && m.counter < *node.last_counter) {
      measure_clock_anew(node, arrival_ns);
      warn("node " + node.endpoint + " started again (its frame counter began anew): its clock is measured anew");
    }
    node.last_counter = m.counter;
    if (!clock_placed(node, arrival_ns)) {
      ++node.stats.unsynchronised;
      return;
    }
    const std::int64_t now = arrival_ns;
    if (!node.stats.connected) {
      node.stats.connected = true;
      if (node.stats.lost > 0) {
        ++node.stats.rejoined;
        warn("node " + node.endpoint + " is back");
      }
    }
    node.stats.node_id = m.node;
    ++node.stats.frames;
    node.last_frame_ns = now;
    camera_last_ns[m.camera] = now;
    CameraMessage cm;
    cm.camera = m.camera;
    cm.counter = m.counter;
    cm.capture_ns = node.clock.to_master(m.capture_ns);
    cm.arrival_ns = arrival_ns;
    cm.detections = std::move(m.detections);
    cm.decode_ns = steady_now_ns() - arrival_ns;
    assembler.add(std::move(cm));
    arrived.notify_all();
  }

  // Forgets a node's clock (it started again, or was lost): its frames wait until it is measured
  // well enough (clock_placed), from replies to requests asked from now on, the first at once.
  static void measure_clock_anew(Node& node, std::int64_t now_ns) {
    node.clock.reset();
    node.placing = false;
    node.measured_from_ns = now_ns;
    node.first_sync_ns = now_ns;
    node.next_sync_ns = 0;
  }

  // Whether a node's frames can be placed in time (from the first that can, until its clock is
  // measured anew): its clock is measured, and every sample its fit uses came back fast enough that
  // the fit is off by a fraction of the assembler's tolerance at most (a sample is off by up to
  // half its round trip). Otherwise one slow first reply (a busy machine, a node just started)
  // places its first frames an exposure off in time, their markers where the scene was one
  // exposure earlier or later. Round trips within 2 ms, or within half again the node's fastest ever
  // (a slower network), are good enough; after a second without (a network slower than it was),
  // the fit there is, with a warning.
  bool clock_placed(Node& node, std::int64_t now_ns) {
    if (!node.clock.synchronised()) return false;
    if (node.placing) return true;
    constexpr double kGoodRtt_us = 2000.0;
    constexpr std::int64_t kWaitForGoodRtt_ns = 1'000'000'000;
    const double good_us = std::max(kGoodRtt_us, 1.5 * static_cast<double>(node.fastest_rtt_ns) / 1e3);
    if (node.clock.fit_rtt_us() <= good_us) {
      node.placing = true;
    } else if (now_ns - node.first_sample_ns > kWaitForGoodRtt_ns) {
      node.placing = true;
      warn("node " + node.endpoint + ": no clock round trip within " + std::to_string(static_cast<int>(good_us)) +
           " us for a second; its frames are placed with round trips of up to " +
           std::to_string(static_cast<int>(node.clock.fit_rtt_us())) + " us, each off by up to half of that");
    }
    return node.placing;
  }

  void on_reply(Node& node, const zmq::message_t& raw, std::int64_t arrival_ns) {
    const auto decoded = decode(std::span(static_cast<const std::uint8_t*>(raw.data()), raw.size()));
    std::lock_guard lock(mutex);
    if (!decoded) {
      ++bad_messages;
      if (worth_telling(++bad_by_kind[static_cast<std::size_t>(decoded.error().kind)]))
        warn("node " + node.endpoint + ": bad reply: " + decoded.error().message);
      return;
    }
    if (const auto* t = std::get_if<TimeReply>(&*decoded)) {
      // A reply to a request of this run only (a restarted node may answer old ones).
      if (t->master_send_ns < opened_ns || t->master_send_ns > arrival_ns || arrival_ns - t->master_send_ns > 1'000'000'000) return;
      if (t->master_send_ns < node.measured_from_ns) return;  // asked of the clock before it was measured anew
      if (node.clock.samples() == 0) node.first_sample_ns = arrival_ns;
      node.clock.add(t->master_send_ns, t->node_ns, arrival_ns);
      node.fastest_rtt_ns = std::min(node.fastest_rtt_ns, arrival_ns - t->master_send_ns);
      node.stats.clock_offset_ms = node.clock.offset_ns_at(arrival_ns) / 1e6;
      node.stats.clock_drift_ppm = node.clock.drift_ppm();
      node.stats.clock_residual_us = node.clock.residual_us();
      node.stats.min_rtt_us = node.clock.min_rtt_us();
    } else if (const auto* s = std::get_if<StatusReply>(&*decoded)) {
      node.stats.node_rate_hz = static_cast<double>(s->frame_rate_hz);
      node.stats.node_detect_ms = static_cast<double>(s->detect_mean_ms);
      node.stats.node_dropped = s->frames_dropped;
    }
  }

  static void send(zmq::socket_t& socket, const std::vector<std::uint8_t>& bytes) {
    // DEALER to REP: an empty delimiter frame, then the request. Not sent while disconnected.
    try {
      if (socket.send(zmq::message_t(), zmq::send_flags::sndmore | zmq::send_flags::dontwait))
        (void)socket.send(zmq::buffer(bytes), zmq::send_flags::dontwait);
    } catch (const zmq::error_t&) {
    }
  }

  void requests(std::int64_t now) {
    for (Node& node : nodes) {
      if (now >= node.next_sync_ns) {
        send(node.control, encode(TimeRequest{node.sequence++, steady_now_ns()}));
        const bool early = now - node.first_sync_ns < 300'000'000 || !node.clock.synchronised() || !node.placing;
        node.next_sync_ns = now + (early ? 10'000'000 : static_cast<std::int64_t>(settings.sync_interval_s * 1e9));
      }
      if (now >= node.next_status_ns) {
        send(node.control, encode(StatusRequest{node.sequence++}));
        node.next_status_ns = now + static_cast<std::int64_t>(settings.status_interval_s * 1e9);
      }
    }
  }

  // (Re)opens a node's frame (SUB) or control (DEALER) socket: its options, its security and
  // handshake monitor, its connection.
  std::expected<void, std::string> open_socket(Node& node, bool frames) {
    zmq::socket_t& socket = frames ? node.frames : node.control;
    std::unique_ptr<HandshakeMonitor>& monitor = frames ? node.frames_monitor : node.control_monitor;
    monitor.reset();
    try {
      socket = zmq::socket_t(context, frames ? zmq::socket_type::sub : zmq::socket_type::dealer);
      socket.set(zmq::sockopt::linger, 0);
      // A peer sending more than any message can be is disconnected by ZeroMQ before it is read.
      socket.set(zmq::sockopt::maxmsgsize, static_cast<std::int64_t>(kMaxNodeMessageBytes));
      socket.set(zmq::sockopt::reconnect_ivl, 100);
      socket.set(zmq::sockopt::reconnect_ivl_max, 500);
      if (frames) {
        socket.set(zmq::sockopt::rcvhwm, 1000);
        socket.set(zmq::sockopt::subscribe, "");
      } else {
        socket.set(zmq::sockopt::immediate, 1);
        socket.set(zmq::sockopt::sndhwm, 16);
      }
      if (node.node_key)
        if (auto ok = make_curve_client(socket.handle(), *settings.security, *node.node_key); !ok) return ok;
      auto attached = HandshakeMonitor::attach(context.handle(), socket.handle());
      if (!attached) return std::unexpected(attached.error());
      monitor = std::move(*attached);
      socket.connect(frames ? node.address : control_endpoint_for(node.address));
    } catch (const zmq::error_t& e) {
      return std::unexpected(std::string(e.what()));
    }
    return {};
  }

  // Sockets due to be opened anew; true when any was (the poll's items change).
  bool reopen_due(std::int64_t now) {
    bool changed = false;
    for (Node& node : nodes)
      for (const bool frames : {true, false}) {
        std::int64_t& due = frames ? node.reopen_frames_ns : node.reopen_control_ns;
        if (due == 0 || now < due) continue;
        due = 0;
        changed = true;
        if (auto ok = open_socket(node, frames); !ok) {
          std::lock_guard lock(mutex);
          warn("node " + node.endpoint + ": cannot open its socket again: " + ok.error());
        }
      }
    return changed;
  }

  void handshakes(Node& node) {
    using Kind = HandshakeMonitor::Event::Kind;
    for (const bool frames : {true, false}) {
      const std::unique_ptr<HandshakeMonitor>& monitor = frames ? node.frames_monitor : node.control_monitor;
      if (!monitor) continue;
      for (const HandshakeMonitor::Event& e : monitor->drain()) {
        const std::int64_t now = steady_now_ns();
        std::int64_t& reopen = frames ? node.reopen_frames_ns : node.reopen_control_ns;
        if (e.kind == Kind::kFailedProtocol || e.kind == Kind::kFailedAuth) reopen = now + kReopenAfter_ns;
        // ZeroMQ reconnects a connection that broke, but not one it ended itself (a message over
        // the size limit, a protocol error): a connection that is not back within
        // kReconnectWait_ns is opened anew.
        if (e.kind == Kind::kDisconnected && reopen == 0) reopen = now + kReconnectWait_ns;
        if (e.kind == Kind::kSucceeded) reopen = 0;
        std::lock_guard lock(mutex);
        if (e.kind == Kind::kConnected) {
          node.connected_ns = now;
        } else if (e.kind == Kind::kSucceeded) {
          if (node.stats.handshake_ms < 0.0 && node.connected_ns > 0)
            node.stats.handshake_ms = static_cast<double>(now - node.connected_ns) / 1e6;
        } else if (e.kind == Kind::kFailedAuth) {
          ++node.stats.handshakes_failed;
          if (worth_telling(++node.stats.refused_by_node))
            warn("node " + node.endpoint + " refused this master's key (status " + std::to_string(e.value) +
                 "): its key folder's trusted/ lacks this master's public certificate (" + std::to_string(node.stats.refused_by_node) +
                 " refusals so far)");
        } else if (e.kind == Kind::kFailedNoDetail || e.kind == Kind::kFailedProtocol) {
          if (worth_telling(++node.stats.handshakes_failed - node.stats.refused_by_node))
            warn("node " + node.endpoint + ": the handshake failed: " +
                 (node.node_key ? "whoever answers there cannot prove it holds " + node.node_name +
                                      "'s secret key, or runs without security, or the bytes on the way were not the node's"
                                : std::string("whoever answers there runs with security, and this master without (--insecure)")) +
                 "; nothing from it is read (" + std::to_string(node.stats.handshakes_failed - node.stats.refused_by_node) + " so far)");
        }
      }
    }
  }

  void liveness(std::int64_t now) {
    std::lock_guard lock(mutex);
    const auto lost_after = static_cast<std::int64_t>(settings.lost_after_s * 1e9);
    for (Node& node : nodes) {
      if (node.stats.connected && now - node.last_frame_ns > lost_after) {
        node.stats.connected = false;
        ++node.stats.lost;
        // Its clock may come back different (a restarted machine): measure it again.
        measure_clock_anew(node, now);
        warn("node " + node.endpoint + " lost: no frame for " + std::to_string(settings.lost_after_s) + " s; tracking goes on without it");
      }
    }
  }

  std::vector<zmq::pollitem_t> poll_items() {
    std::vector<zmq::pollitem_t> items;
    for (Node& node : nodes) {
      items.push_back({node.frames.handle(), 0, ZMQ_POLLIN, 0});
      items.push_back({node.control.handle(), 0, ZMQ_POLLIN, 0});
      for (const auto* monitor : {node.frames_monitor.get(), node.control_monitor.get()})
        if (monitor) items.push_back({monitor->socket(), 0, ZMQ_POLLIN, 0});
    }
    return items;
  }

  void run() {
    std::vector<zmq::pollitem_t> items = poll_items();
    while (!stop.load()) {
      if (const std::int64_t stall = stall_ns.exchange(0); stall > 0) {
        const std::int64_t until = steady_now_ns() + stall;
        while (!stop.load() && steady_now_ns() < until) std::this_thread::sleep_for(std::chrono::milliseconds(5));
      }
      try {
        zmq::poll(items.data(), items.size(), std::chrono::milliseconds(2));
      } catch (const zmq::error_t&) {
        continue;
      }
      for (std::size_t i = 0; i < nodes.size(); ++i) {
        Node& node = nodes[i];
        handshakes(node);
        zmq::message_t message;
        // Everything waiting, so a burst never queues behind the poll.
        while (node.frames.recv(message, zmq::recv_flags::dontwait)) on_frame(node, message, steady_now_ns());
        while (node.control.recv(message, zmq::recv_flags::dontwait)) {
          const std::int64_t at = steady_now_ns();
          if (message.size() == 0 && message.more()) continue;  // the delimiter
          on_reply(node, message, at);
        }
      }
      const std::int64_t now = steady_now_ns();
      requests(now);
      liveness(now);
      if (reopen_due(now)) items = poll_items();
    }
  }

  std::vector<bool> waited_for(std::int64_t now) const {
    const auto lost_after = static_cast<std::int64_t>(settings.lost_after_s * 1e9);
    std::vector<bool> out(rig.cameras.size());
    for (std::size_t c = 0; c < out.size(); ++c) out[c] = camera_last_ns[c] != 0 && now - camera_last_ns[c] <= lost_after;
    return out;
  }

  std::vector<AssembledFrame> take(double wait_s) {
    std::unique_lock lock(mutex);
    const std::int64_t give_up = steady_now_ns() + static_cast<std::int64_t>(wait_s * 1e9);
    for (;;) {
      const std::int64_t now = steady_now_ns();
      std::vector<AssembledFrame> frames = assembler.close(now, waited_for(now));
      const std::int64_t spent = steady_now_ns() - now;
      for (AssembledFrame& f : frames) f.close_cpu_ns = spent / static_cast<std::int64_t>(frames.size());
      if (!frames.empty() || now >= give_up) return frames;
      std::int64_t wake = give_up;
      if (const auto deadline = assembler.next_deadline()) wake = std::min(wake, *deadline);
      arrived.wait_for(lock, std::chrono::nanoseconds(std::max<std::int64_t>(wake - now, 100'000)));
    }
  }
};

NodeSource::NodeSource(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

NodeSource::~NodeSource() {
  if (!impl_) return;
  impl_->stop = true;
  if (impl_->receiver.joinable()) impl_->receiver.join();
}

std::expected<std::unique_ptr<NodeSource>, std::string> NodeSource::open(const CameraRig& rig, std::vector<std::string> endpoints,
                                                                         NodeSourceSettings settings) {
  if (endpoints.empty()) return std::unexpected(std::string("node source: no endpoints"));
  if (rig.cameras.empty()) return std::unexpected(std::string("node source: the rig has no cameras"));
  if (!(settings.lost_after_s > 0.0) || !(settings.max_wait_s >= 0.0) || !(settings.sync_interval_s > 0.0) ||
      !(settings.status_interval_s > 0.0) || settings.assembly.tolerance_ns < 0 ||
      settings.assembly.deadline_ns < settings.assembly.tolerance_ns)
    return std::unexpected(std::string("node source: settings out of range (times must be positive; the deadline at least the tolerance)"));
  auto impl = std::make_unique<Impl>(rig, settings);
  const NetSecurity& security = impl->settings.security;
  try {
    for (const std::string& item : endpoints) {
      const auto address = parse_node_address(item);
      if (!address) return std::unexpected(address.error());
      const std::string& endpoint = address->endpoint;
      const Certificate* node_key = nullptr;
      if (security) {
        if (address->name.empty())
          return std::unexpected("node " + endpoint + ": with keys, name each node as NAME@" + endpoint +
                                 ", NAME.key being its certificate in " + security->dir + "/trusted/");
        node_key = security->trusted_named(address->name);
        if (!node_key) {
          std::string have;
          for (const Certificate& c : security->trusted) have += (have.empty() ? "" : ", ") + c.name;
          return std::unexpected("node " + item + ": no " + security->dir + "/trusted/" + address->name + ".key (it holds " + have + ")");
        }
      }
      Impl::Node node{item, zmq::socket_t(), zmq::socket_t(), ClockSync{}, NodeStats{}};
      node.stats.endpoint = item;
      node.node_name = address->name;
      node.address = endpoint;
      if (node_key) node.node_key = node_key->public_key;
      for (const bool frames : {true, false})
        if (auto ok = impl->open_socket(node, frames); !ok) return std::unexpected("node " + item + ": " + ok.error());
      node.first_sync_ns = steady_now_ns();
      impl->nodes.push_back(std::move(node));
    }
  } catch (const zmq::error_t& e) {
    return std::unexpected(std::string("node source: ") + e.what());
  }
  if (!security) impl->warn(kInsecureWarning);
  Impl* raw = impl.get();
  impl->receiver = std::thread([raw] { raw->run(); });
  return std::unique_ptr<NodeSource>(new NodeSource(std::move(impl)));
}

const CameraRig& NodeSource::rig() const { return impl_->rig; }
std::int64_t NodeSource::origin_ns() const { return impl_->origin_ns; }

std::vector<AssembledFrame> NodeSource::take_frames(double wait_s) { return impl_->take(wait_s); }

RigFrame NodeSource::to_rig_frame(const AssembledFrame& f) const {
  RigFrame out;
  out.time_s = static_cast<double>(f.capture_ns - impl_->origin_ns) / 1e9;
  out.capture_steady_s = static_cast<double>(f.capture_ns) / 1e9;  // the nodes' clocks mapped onto this host's steady clock
  out.cameras.resize(impl_->rig.cameras.size());
  for (std::size_t c = 0; c < out.cameras.size(); ++c) {
    out.cameras[c].camera = static_cast<int>(c);
    out.cameras[c].timestamp_s = out.time_s;
    out.cameras[c].delivered = c < f.cameras.size() && f.cameras[c].has_value();
    if (out.cameras[c].delivered) {
      out.cameras[c].timestamp_s = static_cast<double>(f.cameras[c]->capture_ns - impl_->origin_ns) / 1e9;
      out.cameras[c].detections = f.cameras[c]->detections;
    }
  }
  return out;
}

std::optional<RigFrame> NodeSource::next(double) {
  std::vector<AssembledFrame> frames = impl_->take(impl_->settings.max_wait_s);
  RigFrame out;
  if (frames.empty()) {
    out.time_s = static_cast<double>(steady_now_ns() - impl_->origin_ns) / 1e9;
    out.cameras.resize(impl_->rig.cameras.size());
    for (std::size_t c = 0; c < out.cameras.size(); ++c) {
      out.cameras[c].camera = static_cast<int>(c);
      out.cameras[c].delivered = false;
    }
  } else {
    out = to_rig_frame(frames.back());
  }
  std::lock_guard lock(impl_->mutex);
  if (!frames.empty()) impl_->superseded += frames.size() - 1;
  out.index = impl_->frame_index++;
  return out;
}

std::vector<std::string> NodeSource::take_warnings() {
  std::lock_guard lock(impl_->mutex);
  return std::exchange(impl_->warnings, {});
}

void NodeSource::stall_receiver(double seconds) { impl_->stall_ns = static_cast<std::int64_t>(std::max(0.0, seconds) * 1e9); }

NodeSourceStats NodeSource::stats() const {
  std::lock_guard lock(impl_->mutex);
  NodeSourceStats s;
  s.assembly = impl_->assembler.counts();
  s.superseded = impl_->superseded;
  s.bad_messages = impl_->bad_messages;
  for (const auto& node : impl_->nodes) s.nodes.push_back(node.stats);
  return s;
}

std::vector<std::string> NodeSource::summary() const {
  const NodeSourceStats s = stats();
  std::vector<std::string> out;
  char line[512];
  for (const NodeStats& n : s.nodes) {
    std::snprintf(line, sizeof line,
                  "node %s (id %d): %s, %llu frames, %llu bytes, lost %llu times, clock %+.3f ms %+.1f ppm (residual %.0f us), "
                  "node rate %.1f Hz, detection %.3f ms, %llu dropped on the node",
                  n.endpoint.c_str(), n.node_id, n.connected ? "connected" : "not connected", static_cast<unsigned long long>(n.frames),
                  static_cast<unsigned long long>(n.bytes), static_cast<unsigned long long>(n.lost), n.clock_offset_ms, n.clock_drift_ppm,
                  n.clock_residual_us, n.node_rate_hz, n.node_detect_ms, static_cast<unsigned long long>(n.node_dropped));
    out.emplace_back(line);
  }
  std::snprintf(
      line, sizeof line,
      "assembly: %llu frames (%llu complete, %llu closed by the deadline), %llu late, %llu duplicate, %llu out of order, %llu bad",
      static_cast<unsigned long long>(s.assembly.frames), static_cast<unsigned long long>(s.assembly.complete_frames),
      static_cast<unsigned long long>(s.assembly.deadline_frames), static_cast<unsigned long long>(s.assembly.late),
      static_cast<unsigned long long>(s.assembly.duplicates), static_cast<unsigned long long>(s.assembly.out_of_order),
      static_cast<unsigned long long>(s.bad_messages));
  out.emplace_back(line);
  return out;
}

}  // namespace rhot
