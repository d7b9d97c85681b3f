#pragma once
// CURVE on the camera network's ZeroMQ sockets (docs/camera-nodes.md, "Security"). A node binds
// and is the CURVE server: it proves it holds its secret key, and its ZAP handler admits only the
// masters whose public keys its key folder trusts. A master connects and is the CURVE client: it
// holds the node's public key, so a peer that cannot prove it holds the matching secret is never
// heard. Sockets are ZeroMQ's C handles (void*), so no ZeroMQ type crosses this header.

#include <cstdint>
#include <expected>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "tracking/net/CurveKeys.h"

namespace rhot {

// Before a socket binds or connects: a node's socket as CURVE server with the ring's own key (and
// ZAP domain "rhot"; a ZapHandler on the same context decides who may connect), a master's as
// CURVE client of the node whose public key is `node_key`. The handshake is given kHandshakeMs:
// a peer that connects and says nothing is dropped, not kept.
inline constexpr int kHandshakeMs = 2000;

// What a node or a master opened without keys says (in its warnings) as it starts.
inline constexpr const char* kInsecureWarning =
    "INSECURE: camera nodes without authentication or encryption (--insecure): anyone on the camera network can read the markers and "
    "send false ones (docs/camera-nodes.md, \"Security\")";
[[nodiscard]] std::expected<void, std::string> make_curve_server(void* socket, const KeyRing& keys);
[[nodiscard]] std::expected<void, std::string> make_curve_client(void* socket, const KeyRing& keys, const CurveKey& node_key);

// A node's ZAP handler (ZeroMQ's authentication protocol, RFC 27), bound in its context before any
// of its sockets: a CURVE client whose public key the ring trusts is admitted, anyone else refused.
// Without a handler ZeroMQ admits every CURVE client, so a node with keys has one.
class ZapHandler {
 public:
  [[nodiscard]] static std::expected<std::unique_ptr<ZapHandler>, std::string> bind(void* context, const KeyRing& keys);
  ~ZapHandler();
  ZapHandler(const ZapHandler&) = delete;
  ZapHandler& operator=(const ZapHandler&) = delete;

  void* socket() const { return socket_; }  // to poll
  struct Decision {
    bool admitted = false;
    std::string address;    // the peer's IP address
    std::string mechanism;  // "CURVE"; "NULL" or "PLAIN" are refused
    std::optional<CurveKey> key;
  };
  // Answers every waiting request (without blocking), returning what it decided.
  std::vector<Decision> answer();

 private:
  ZapHandler(void* socket, const KeyRing& keys) : socket_(socket), keys_(keys) {}
  void* socket_;
  KeyRing keys_;
};

// Handshake outcomes of one socket (ZeroMQ's socket monitor over an inproc pair).
class HandshakeMonitor {
 public:
  // Every event below, or (failures_only: a node's, where anyone may connect and hang up) only
  // the failed handshakes. ZeroMQ's I/O thread waits while the monitor's pipe is full, so a socket
  // that strangers reach is told only what it counts, and drained often.
  [[nodiscard]] static std::expected<std::unique_ptr<HandshakeMonitor>, std::string> attach(void* context, void* socket,
                                                                                            bool failures_only = false);
  ~HandshakeMonitor();
  HandshakeMonitor(const HandshakeMonitor&) = delete;
  HandshakeMonitor& operator=(const HandshakeMonitor&) = delete;

  void* socket() const { return pair_; }  // to poll
  struct Event {
    enum class Kind : std::uint8_t {
      kConnected,  // TCP (or IPC) connected; the handshake begins
      kSucceeded,
      kFailedNoDetail,  // the peer hung up in the handshake: it could not prove the key we hold, or speaks no CURVE
      kFailedProtocol,  // a malformed or mismatched handshake (one side without security)
      kFailedAuth,      // the peer's ZAP handler refused us (the value: its status code)
      kDisconnected,
    };
    Kind kind = Kind::kConnected;
    std::uint32_t value = 0;
    std::string address;
  };
  std::vector<Event> drain();

 private:
  HandshakeMonitor(void* watched, void* pair) : watched_(watched), pair_(pair) {}
  void* watched_;
  void* pair_;
};

}  // namespace rhot
