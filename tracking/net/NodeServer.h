#pragma once
// A camera node's sockets (rhot-node): frames out on a PUB socket, time and status requests
// answered on a REP socket beside it (docs/camera-nodes.md). It binds exactly the endpoints it is
// given. A subscriber that cannot keep up loses frames at the PUB socket's high-water mark; the
// node never blocks on the network.
//
// With a key folder (CurveKeys.h) both sockets speak CURVE as its server: every frame and reply is
// encrypted, and only the masters the folder trusts get through the handshake (SocketSecurity.h,
// ZapHandler); refusals are counted and told at the 1st, 10th, 100th ... (take_warnings). Without
// one (--insecure) anyone who reaches the endpoints reads the frames.

#include <cstdint>
#include <expected>
#include <memory>
#include <string>
#include <vector>

#include "tracking/net/CurveKeys.h"
#include "tracking/net/NodeProtocol.h"

namespace rhot {

// The node's clock: the machine's steady clock, optionally made wrong on purpose (to test the
// master's synchronisation): node = true + offset + drift * (true - start).
struct NodeClock {
  std::int64_t offset_ns = 0;
  double drift_ppm = 0.0;
  std::int64_t start_ns = 0;
  std::int64_t node_ns(std::int64_t true_ns) const;
};

struct NodeServerStats {
  std::uint64_t frames_published = 0;
  std::uint64_t frames_dropped = 0;  // set by the caller: exposures it could not process in time
  std::uint64_t requests = 0;
  std::uint64_t bad_requests = 0;
  double frame_rate_hz = 0.0;           // set by the caller
  double detect_mean_ms = 0.0;          // set by the caller
  std::uint64_t masters_admitted = 0;   // handshakes the ZAP handler let through (a master connects both sockets)
  std::uint64_t peers_refused = 0;      // CURVE clients whose key the folder does not trust
  std::uint64_t handshakes_failed = 0;  // peers that broke off or spoke another mechanism (plaintext)
};

class NodeServer {
 public:
  // Binds publish and control (each checked by check_endpoint), with CURVE when `security` holds a
  // key folder. Fails naming the endpoint when it is malformed or taken.
  [[nodiscard]] static std::expected<std::unique_ptr<NodeServer>, std::string> open(const std::string& publish, const std::string& control,
                                                                                    std::uint16_t node_id, std::uint16_t cameras,
                                                                                    NodeClock clock, const NetSecurity& security);
  ~NodeServer();
  NodeServer(const NodeServer&) = delete;
  NodeServer& operator=(const NodeServer&) = delete;

  void publish(const NodeFrameMessage& frame);
  // Answers requests until the steady clock reaches until_ns (returns at once if it has).
  void serve_until(std::int64_t until_ns);
  NodeServerStats& stats();
  // What the node has to tell since the last call (refused peers, at the 1st, 10th, 100th ...).
  std::vector<std::string> take_warnings();
  const NodeClock& clock() const;

 private:
  struct Impl;
  explicit NodeServer(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace rhot
