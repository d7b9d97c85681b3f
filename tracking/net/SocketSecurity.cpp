#include "tracking/net/SocketSecurity.h"

#include <atomic>
#include <cstring>

#include <zmq.h>

namespace rhot {

namespace {

std::expected<void, std::string> set_option(void* socket, int option, const void* value, std::size_t size, const char* what) {
  if (zmq_setsockopt(socket, option, value, size) != 0) return std::unexpected(std::string(what) + ": " + zmq_strerror(zmq_errno()));
  return {};
}

std::expected<void, std::string> set_int(void* socket, int option, int value, const char* what) {
  return set_option(socket, option, &value, sizeof value, what);
}

// Every frame of one multi-part message (false when nothing was waiting or it broke off).
bool receive_parts(void* socket, std::vector<std::string>& parts) {
  parts.clear();
  for (;;) {
    zmq_msg_t msg;
    zmq_msg_init(&msg);
    if (zmq_msg_recv(&msg, socket, parts.empty() ? ZMQ_DONTWAIT : 0) < 0) {
      zmq_msg_close(&msg);
      return false;
    }
    parts.emplace_back(static_cast<const char*>(zmq_msg_data(&msg)), zmq_msg_size(&msg));
    const bool more = zmq_msg_more(&msg) != 0;
    zmq_msg_close(&msg);
    if (!more) return true;
    if (parts.size() > 16) {  // not a ZAP request; read the rest and drop it
      int m = 1;
      while (m) {
        zmq_msg_init(&msg);
        if (zmq_msg_recv(&msg, socket, 0) < 0)
          m = 0;
        else
          m = zmq_msg_more(&msg);
        zmq_msg_close(&msg);
      }
      parts.clear();
      return true;
    }
  }
}

}  // namespace

std::expected<void, std::string> make_curve_server(void* socket, const KeyRing& keys) {
  if (!keys.own.secret_key) return std::unexpected(keys.own.path + ": no secret key");
  if (auto ok = set_int(socket, ZMQ_CURVE_SERVER, 1, "CURVE server"); !ok) return ok;
  if (auto ok = set_option(socket, ZMQ_CURVE_SECRETKEY, keys.own.secret_key->bytes.data(), 32, "CURVE secret key"); !ok) return ok;
  if (auto ok = set_option(socket, ZMQ_ZAP_DOMAIN, "rhot", 4, "ZAP domain"); !ok) return ok;
  return set_int(socket, ZMQ_HANDSHAKE_IVL, kHandshakeMs, "handshake interval");
}

std::expected<void, std::string> make_curve_client(void* socket, const KeyRing& keys, const CurveKey& node_key) {
  if (!keys.own.secret_key) return std::unexpected(keys.own.path + ": no secret key");
  if (auto ok = set_option(socket, ZMQ_CURVE_SERVERKEY, node_key.bytes.data(), 32, "CURVE server key"); !ok) return ok;
  if (auto ok = set_option(socket, ZMQ_CURVE_PUBLICKEY, keys.own.public_key.bytes.data(), 32, "CURVE public key"); !ok) return ok;
  if (auto ok = set_option(socket, ZMQ_CURVE_SECRETKEY, keys.own.secret_key->bytes.data(), 32, "CURVE secret key"); !ok) return ok;
  return set_int(socket, ZMQ_HANDSHAKE_IVL, kHandshakeMs, "handshake interval");
}

std::expected<std::unique_ptr<ZapHandler>, std::string> ZapHandler::bind(void* context, const KeyRing& keys) {
  void* socket = zmq_socket(context, ZMQ_REP);
  if (socket == nullptr) return std::unexpected(std::string("ZAP handler: ") + zmq_strerror(zmq_errno()));
  const int linger = 0;
  zmq_setsockopt(socket, ZMQ_LINGER, &linger, sizeof linger);
  if (zmq_bind(socket, "inproc://zeromq.zap.01") != 0) {
    const std::string why = zmq_strerror(zmq_errno());
    zmq_close(socket);
    return std::unexpected("ZAP handler: " + why);
  }
  return std::unique_ptr<ZapHandler>(new ZapHandler(socket, keys));
}

ZapHandler::~ZapHandler() { zmq_close(socket_); }

std::vector<ZapHandler::Decision> ZapHandler::answer() {
  std::vector<Decision> out;
  std::vector<std::string> parts;
  while (receive_parts(socket_, parts)) {
    // version, request id, domain, address, identity, mechanism, credentials...
    Decision d;
    std::string request_id;
    if (parts.size() >= 6 && parts[0] == "1.0") {
      request_id = parts[1];
      d.address = parts[3];
      d.mechanism = parts[5];
      if (d.mechanism == "CURVE" && parts.size() == 7 && parts[6].size() == 32) {
        CurveKey key;
        std::memcpy(key.bytes.data(), parts[6].data(), 32);
        d.key = key;
        d.admitted = keys_.trusts(key);
      }
    }
    const std::string status = d.admitted ? "200" : "400";
    const std::string text = d.admitted ? "OK" : d.key ? "key not trusted" : "CURVE only";
    const std::string reply[] = {"1.0", request_id, status, text, d.admitted ? d.key->z85() : std::string(), ""};
    // A reply that cannot be sent leaves the handshake to time out (kHandshakeMs): refused either way.
    for (std::size_t i = 0; i < 6; ++i)
      if (zmq_send(socket_, reply[i].data(), reply[i].size(), i + 1 < 6 ? ZMQ_SNDMORE : 0) < 0) break;
    out.push_back(std::move(d));
  }
  return out;
}

std::expected<std::unique_ptr<HandshakeMonitor>, std::string> HandshakeMonitor::attach(void* context, void* socket, bool failures_only) {
  static std::atomic<unsigned long long> next{0};
  const std::string endpoint = "inproc://rhot-handshake-monitor-" + std::to_string(next++);
  const int failures = ZMQ_EVENT_HANDSHAKE_FAILED_NO_DETAIL | ZMQ_EVENT_HANDSHAKE_FAILED_PROTOCOL | ZMQ_EVENT_HANDSHAKE_FAILED_AUTH;
  const int events = failures_only
                         ? failures
                         : failures | ZMQ_EVENT_CONNECTED | ZMQ_EVENT_ACCEPTED | ZMQ_EVENT_DISCONNECTED | ZMQ_EVENT_HANDSHAKE_SUCCEEDED;
  if (zmq_socket_monitor(socket, endpoint.c_str(), events) != 0)
    return std::unexpected(std::string("socket monitor: ") + zmq_strerror(zmq_errno()));
  void* pair = zmq_socket(context, ZMQ_PAIR);
  if (pair == nullptr || zmq_connect(pair, endpoint.c_str()) != 0) {
    const std::string why = zmq_strerror(zmq_errno());
    if (pair) zmq_close(pair);
    zmq_socket_monitor(socket, nullptr, 0);
    return std::unexpected("socket monitor: " + why);
  }
  const int linger = 0;
  zmq_setsockopt(pair, ZMQ_LINGER, &linger, sizeof linger);
  return std::unique_ptr<HandshakeMonitor>(new HandshakeMonitor(socket, pair));
}

HandshakeMonitor::~HandshakeMonitor() {
  zmq_socket_monitor(watched_, nullptr, 0);
  zmq_close(pair_);
}

std::vector<HandshakeMonitor::Event> HandshakeMonitor::drain() {
  std::vector<Event> out;
  std::vector<std::string> parts;
  while (receive_parts(pair_, parts)) {
    if (parts.size() != 2 || parts[0].size() != 6) continue;
    std::uint16_t id = 0;
    Event e;
    std::memcpy(&id, parts[0].data(), 2);
    std::memcpy(&e.value, parts[0].data() + 2, 4);
    e.address = parts[1];
    switch (id) {
      case ZMQ_EVENT_CONNECTED:
      case ZMQ_EVENT_ACCEPTED:
        e.kind = Event::Kind::kConnected;
        break;
      case ZMQ_EVENT_HANDSHAKE_SUCCEEDED:
        e.kind = Event::Kind::kSucceeded;
        break;
      case ZMQ_EVENT_HANDSHAKE_FAILED_NO_DETAIL:
        e.kind = Event::Kind::kFailedNoDetail;
        break;
      case ZMQ_EVENT_HANDSHAKE_FAILED_PROTOCOL:
        e.kind = Event::Kind::kFailedProtocol;
        break;
      case ZMQ_EVENT_HANDSHAKE_FAILED_AUTH:
        e.kind = Event::Kind::kFailedAuth;
        break;
      case ZMQ_EVENT_DISCONNECTED:
        e.kind = Event::Kind::kDisconnected;
        break;
      default:
        continue;
    }
    out.push_back(std::move(e));
  }
  return out;
}

}  // namespace rhot
