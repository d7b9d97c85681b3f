#include "tracking/net/NodeServer.h"

#include <chrono>
#include <cmath>
#include <thread>
#include <utility>
#include <vector>

#include <zmq.hpp>

#include "tracking/net/NodeSource.h"
#include "tracking/net/SocketSecurity.h"

namespace rhot {

std::int64_t NodeClock::node_ns(std::int64_t true_ns) const {
  return true_ns + offset_ns + static_cast<std::int64_t>(std::llround(drift_ppm * 1e-6 * static_cast<double>(true_ns - start_ns)));
}

struct NodeServer::Impl {
  zmq::context_t context{1};
  // Declared (and so bound) before the sockets it guards, destroyed after them.
  std::unique_ptr<ZapHandler> zap;
  zmq::socket_t frames{context, zmq::socket_type::pub};
  zmq::socket_t control{context, zmq::socket_type::rep};
  std::vector<std::unique_ptr<HandshakeMonitor>> monitors;  // with security: the two sockets' handshakes
  std::uint16_t node_id = 0;
  std::uint16_t cameras = 0;
  NodeClock clock;
  NodeServerStats stats;
  std::string keys_dir;
  std::vector<std::string> warnings;

  void warn(std::string line) {
    if (warnings.size() < 1000) warnings.push_back(std::move(line));
  }

  void check_peers() {
    if (zap) {
      for (const ZapHandler::Decision& d : zap->answer()) {
        if (d.admitted) {
          ++stats.masters_admitted;
          continue;
        }
        if (worth_telling(++stats.peers_refused))
          warn("refused a peer at " + (d.address.empty() ? std::string("an unknown address") : d.address) +
               (d.key ? " with the key " + d.key->z85() + ", which " + keys_dir + "/trusted/ does not hold"
                      : " without a CURVE key (" + d.mechanism + ")") +
               " (" + std::to_string(stats.peers_refused) + " refused so far)");
      }
    }
    for (const auto& monitor : monitors)
      for (const HandshakeMonitor::Event& e : monitor->drain()) {
        using Kind = HandshakeMonitor::Event::Kind;
        if (e.kind != Kind::kFailedNoDetail && e.kind != Kind::kFailedProtocol) continue;
        if (worth_telling(++stats.handshakes_failed))
          warn("a peer failed the handshake on " + e.address + " (it speaks no CURVE, or broke off; " +
               std::to_string(stats.handshakes_failed) + " so far)");
      }
  }

  void answer(const zmq::message_t& request) {
    ++stats.requests;
    const auto decoded = decode(std::span(static_cast<const std::uint8_t*>(request.data()), request.size()));
    std::vector<std::uint8_t> reply;
    if (decoded && std::holds_alternative<TimeRequest>(*decoded)) {
      const auto& t = std::get<TimeRequest>(*decoded);
      reply = encode(TimeReply{t.sequence, t.master_send_ns, clock.node_ns(steady_now_ns())});
    } else if (decoded && std::holds_alternative<StatusRequest>(*decoded)) {
      StatusReply s;
      s.sequence = std::get<StatusRequest>(*decoded).sequence;
      s.node = node_id;
      s.cameras = cameras;
      s.frame_rate_hz = static_cast<float>(stats.frame_rate_hz);
      s.detect_mean_ms = static_cast<float>(stats.detect_mean_ms);
      s.frames_published = stats.frames_published;
      s.frames_dropped = stats.frames_dropped;
      reply = encode(s);
    } else {
      // REP must answer every request: a status reply with sequence 0 and nothing else says "not understood".
      ++stats.bad_requests;
      reply = encode(StatusReply{});
    }
    (void)control.send(zmq::buffer(reply), zmq::send_flags::dontwait);
  }
};

NodeServer::NodeServer(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
NodeServer::~NodeServer() = default;

std::expected<std::unique_ptr<NodeServer>, std::string> NodeServer::open(const std::string& publish, const std::string& control,
                                                                         std::uint16_t node_id, std::uint16_t cameras, NodeClock clock,
                                                                         const NetSecurity& security) {
  for (const std::string* e : {&publish, &control})
    if (auto ok = check_endpoint(*e); !ok) return std::unexpected(ok.error());
  auto impl = std::make_unique<Impl>();
  impl->node_id = node_id;
  impl->cameras = cameras;
  impl->clock = clock;
  if (!security) impl->warn(kInsecureWarning);
  if (security) {
    impl->keys_dir = security->dir;
    auto zap = ZapHandler::bind(impl->context.handle(), *security);
    if (!zap) return std::unexpected(zap.error());
    impl->zap = std::move(*zap);
    for (zmq::socket_t* socket : {&impl->frames, &impl->control}) {
      if (auto ok = make_curve_server(socket->handle(), *security); !ok) return std::unexpected("node security: " + ok.error());
      auto monitor = HandshakeMonitor::attach(impl->context.handle(), socket->handle(), true);
      if (!monitor) return std::unexpected(monitor.error());
      impl->monitors.push_back(std::move(*monitor));
    }
  }
  try {
    impl->frames.set(zmq::sockopt::linger, 0);
    impl->frames.set(zmq::sockopt::sndhwm, 1000);
    impl->frames.set(zmq::sockopt::maxmsgsize, static_cast<std::int64_t>(kMaxNodeMessageBytes));
    impl->frames.bind(publish);
  } catch (const zmq::error_t& e) {
    return std::unexpected("cannot publish on " + publish + ": " + e.what());
  }
  try {
    impl->control.set(zmq::sockopt::linger, 0);
    // A peer sending more than any request can be is disconnected by ZeroMQ before it is read.
    impl->control.set(zmq::sockopt::maxmsgsize, static_cast<std::int64_t>(kMaxNodeMessageBytes));
    impl->control.bind(control);
  } catch (const zmq::error_t& e) {
    return std::unexpected("cannot answer requests on " + control + ": " + e.what());
  }
  return std::unique_ptr<NodeServer>(new NodeServer(std::move(impl)));
}

void NodeServer::publish(const NodeFrameMessage& frame) {
  const std::vector<std::uint8_t> bytes = encode(frame);
  try {
    if (impl_->frames.send(zmq::buffer(bytes), zmq::send_flags::dontwait)) ++impl_->stats.frames_published;
  } catch (const zmq::error_t&) {
  }
}

void NodeServer::serve_until(std::int64_t until_ns) {
  for (;;) {
    const std::int64_t now = steady_now_ns();
    if (now >= until_ns) return;
    std::vector<zmq::pollitem_t> items{{impl_->control.handle(), 0, ZMQ_POLLIN, 0}};
    if (impl_->zap) items.push_back({impl_->zap->socket(), 0, ZMQ_POLLIN, 0});
    for (const auto& monitor : impl_->monitors) items.push_back({monitor->socket(), 0, ZMQ_POLLIN, 0});
    const zmq::pollitem_t& item = items[0];
    // zmq_poll's timeout is in milliseconds: poll at most 1 ms, then sleep the sub-millisecond rest.
    const std::int64_t left = until_ns - now;
    try {
      if (left >= 1'000'000) {
        zmq::poll(items.data(), items.size(), std::chrono::milliseconds(1));
        impl_->check_peers();
      } else {
        zmq::poll(items.data(), items.size(), std::chrono::milliseconds(0));
        impl_->check_peers();
        if (!(item.revents & ZMQ_POLLIN)) {
          std::this_thread::sleep_for(std::chrono::nanoseconds(std::min<std::int64_t>(left, 200'000)));
          continue;
        }
      }
    } catch (const zmq::error_t&) {
      return;
    }
    zmq::message_t request;
    try {
      while (impl_->control.recv(request, zmq::recv_flags::dontwait)) {
        // A request is one frame; the rest of a multi-part one is read and it is answered as not understood.
        bool multipart = false;
        zmq::message_t rest;
        while (request.more() && impl_->control.recv(rest, zmq::recv_flags::dontwait)) {
          multipart = true;
          if (!rest.more()) break;
        }
        if (multipart) request.rebuild(std::size_t{0});
        impl_->answer(request);
      }
    } catch (const zmq::error_t&) {
      // A peer that broke the request-reply rhythm: nothing to answer; the socket goes on.
    }
  }
}

NodeServerStats& NodeServer::stats() { return impl_->stats; }
std::vector<std::string> NodeServer::take_warnings() { return std::exchange(impl_->warnings, {}); }
const NodeClock& NodeServer::clock() const { return impl_->clock; }

}  // namespace rhot
