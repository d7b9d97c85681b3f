#pragma once
// Frames from camera nodes (rhot-node) over ZeroMQ: the master's side of docs/camera-nodes.md.
//
// One receiving thread owns every socket: per node a SUB socket on its publish endpoint (its
// frames) and a DEALER on its control endpoint (time and status requests). It decodes each frame
// (bad messages counted and logged at the 1st, 10th, 100th ... of each kind), puts its capture
// time on the master's clock through that node's ClockSync, and hands it to a FrameAssembler.
// next() returns the newest closed multi-camera frame: it waits for the missing cameras only up
// to the assembly deadline, so a slow or silent node never stalls the runtime.
//
// A frame's camera number is the rig's: each node is told which rig cameras it serves. A camera
// from which nothing came for lost_after_s is lost: no longer waited for, shown in the warnings,
// stats() and summary(); it rejoins with its next frame (ZeroMQ reconnects by itself). The clock:
// the steady clock of the master's machine, in nanoseconds; RigFrame::time_s counts from open().
//
// With a key folder (NodeSourceSettings::security, CurveKeys.h) each node is named in the list as
// NAME@ENDPOINT, NAME being its public certificate in the folder's trusted/ (NAME.key): the
// master is the CURVE client of that key (SocketSecurity.h), so whatever answers at the endpoint
// without the matching secret key is never heard, and everything on the wire is encrypted. Failed
// handshakes are counted per node and told at the 1st, 10th, 100th ...

#include <cstdint>
#include <expected>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "tracking/camera/Camera.h"
#include "tracking/net/CurveKeys.h"
#include "tracking/net/FrameAssembler.h"
#include "tracking/source/FrameSource.h"

namespace rhot {

// The master's clock: the machine's steady clock in nanoseconds (CLOCK_MONOTONIC on Linux).
std::int64_t steady_now_ns();

// An endpoint a node may be told to use: tcp://HOST:PORT (HOST an address or a name, PORT
// 1-65534, so that PORT + 1 exists), ipc://PATH or inproc://NAME. "*" binds everywhere and is
// refused unless allow_wildcard: a node binds only where it is told. Fails naming what is wrong.
[[nodiscard]] std::expected<void, std::string> check_endpoint(const std::string& endpoint, bool allow_wildcard = false);
// A node's control endpoint beside its publish endpoint: tcp port + 1, or PATH.control.
std::string control_endpoint_for(const std::string& publish);
// One node of a master's list: NAME@ENDPOINT, or ENDPOINT without a name (a master without keys).
struct NodeAddress {
  std::string name;  // its certificate's name (NAME.key in the master's trusted keys); empty: none given
  std::string endpoint;
};
[[nodiscard]] std::expected<NodeAddress, std::string> parse_node_address(const std::string& item);
// "node0@tcp://127.0.0.1:5601,node1@tcp://127.0.0.1:5603" -> the items as given, each checked
// (parse_node_address), no endpoint twice.
[[nodiscard]] std::expected<std::vector<std::string>, std::string> parse_node_endpoints(const std::string& list);

// `count` loopback TCP ports P, each with P + 1 free too (a node's publish and control ports),
// that nothing listens on at the moment of asking: for tools and tests that start nodes.
[[nodiscard]] std::expected<std::vector<int>, std::string> free_tcp_port_pairs(int count);

struct NodeSourceSettings {
  AssemblySettings assembly;
  double lost_after_s = 0.5;       // a camera silent this long is lost
  double max_wait_s = 0.02;        // next() waits at most this long for a frame
  double sync_interval_s = 0.05;   // time requests per node (every 10 ms for the first 0.3 s)
  double status_interval_s = 1.0;  // status requests per node
  // RigFrame::time_s counts from this moment of the master's clock (empty: open()). A simulation
  // shared by nodes and master sets it to the simulated world's time 0.
  std::optional<std::int64_t> time_origin_ns;
  // The master's key folder (its own secret key; in trusted/ each node's public certificate), or
  // none: --insecure, every node heard, nothing encrypted.
  NetSecurity security;
};

struct NodeStats {
  std::string endpoint;
  bool connected = false;  // a frame came within lost_after_s
  int node_id = -1;        // from its frames (-1: none yet)
  std::uint64_t frames = 0;
  std::uint64_t bytes = 0;
  std::uint64_t unsynchronised = 0;  // frames dropped before its clock was measured well enough (NodeSource.cpp, clock_placed)
  std::uint64_t lost = 0;            // times it was lost
  std::uint64_t rejoined = 0;        // times it came back after being lost
  double clock_offset_ms = 0.0;      // node ahead of master
  double clock_drift_ppm = 0.0;
  double clock_residual_us = 0.0;
  double min_rtt_us = 0.0;
  // Security: handshakes that failed (whoever answers cannot prove the node's key, or runs without
  // security), those of them the node refused (it does not trust this master's key), and the
  // first connection's handshake time (from the TCP connection to its success; -1: none yet).
  std::uint64_t handshakes_failed = 0;
  std::uint64_t refused_by_node = 0;
  double handshake_ms = -1.0;
  // From its latest status reply.
  double node_rate_hz = 0.0;
  double node_detect_ms = 0.0;
  std::uint64_t node_dropped = 0;
};

struct NodeSourceStats {
  AssemblyCounts assembly;
  std::uint64_t superseded = 0;  // closed frames next() skipped for a newer one
  std::uint64_t bad_messages = 0;
  std::vector<NodeStats> nodes;
};

class NodeSource final : public FrameSource {
 public:
  // Connects (ZeroMQ connects lazily: a node that is not up yet is simply not heard from yet).
  // Fails on a bad endpoint or an empty list.
  [[nodiscard]] static std::expected<std::unique_ptr<NodeSource>, std::string> open(const CameraRig& rig,
                                                                                    std::vector<std::string> endpoints,
                                                                                    NodeSourceSettings settings = {});
  ~NodeSource() override;
  NodeSource(const NodeSource&) = delete;
  NodeSource& operator=(const NodeSource&) = delete;

  // FrameSource: the newest frame closed by now, waiting up to max_wait_s for one; with nothing
  // from any node, a frame with no detections. Never ends.
  std::optional<RigFrame> next(double t_s) override;
  const CameraRig& rig() const override;
  std::vector<std::string> take_warnings() override;
  std::vector<std::string> summary() const override;

  // Every frame closed by now, oldest first, waiting up to wait_s for the first (for evaluations
  // that must see each frame).
  std::vector<AssembledFrame> take_frames(double wait_s);
  // An assembled frame as the tracker takes it (time_s from the settings' time origin).
  RigFrame to_rig_frame(const AssembledFrame& frame) const;
  // The master's clock at the time origin (open(), unless the settings name one).
  std::int64_t origin_ns() const;
  NodeSourceStats stats() const;
  // For evaluations and tests: the receiving thread does nothing for `seconds` from its next turn,
  // as on a machine that stalled (its sockets queue what comes meanwhile).
  void stall_receiver(double seconds);

 private:
  struct Impl;
  explicit NodeSource(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace rhot
