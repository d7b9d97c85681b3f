#pragma once

// The camera network's security flags, the same in every program that talks to camera nodes
// (rhot-node, rhot-demo, rhot-calib record and headset, rhot-eval nodes; docs/camera-nodes.md,
// "Security"): --keys DIR (its own NAME.key_secret, and in DIR/trusted/ the public certificates
// of the peers it trusts) or --insecure, one of them, whenever nodes are used. Running insecure is
// said on every start, by the node's and the master's sockets themselves (SocketSecurity.h).

#include <expected>
#include <string>

#include <CLI/CLI.hpp>

#include "tracking/net/CurveKeys.h"

namespace rhot {

struct NodeKeyFlags {
  std::string keys;
  bool insecure = false;
};

inline void add_node_key_flags(CLI::App& app, NodeKeyFlags& flags) {
  app.add_option("--keys", flags.keys,
                 "The camera network's keys: a folder with this program's own NAME.key_secret and, in trusted/, the public "
                 "certificates (NAME.key) of the peers it trusts (rhot-node keygen makes them; docs/camera-nodes.md)");
  app.add_flag("--insecure", flags.insecure,
               "Talk to camera nodes without authentication or encryption: anyone on the camera network can read the markers and "
               "send false ones");
}

// The security the flags ask for, its keys loaded and checked (`using_nodes`: whether this run
// talks to nodes at all; the flags are refused otherwise).
[[nodiscard]] inline std::expected<NetSecurity, std::string> node_security_from(const NodeKeyFlags& flags, bool using_nodes) {
  if (!using_nodes) {
    if (!flags.keys.empty()) return std::unexpected(std::string("--keys: only for camera nodes"));
    if (flags.insecure) return std::unexpected(std::string("--insecure: only for camera nodes"));
    return NetSecurity{};
  }
  if (!flags.keys.empty() && flags.insecure) return std::unexpected(std::string("--keys and --insecure: choose one"));
  if (flags.insecure) return NetSecurity{};
  if (flags.keys.empty())
    return std::unexpected(std::string(
        "camera nodes need --keys DIR (this program's NAME.key_secret, and the peers' NAME.key in DIR/trusted/; rhot-node keygen makes "
        "them) or --insecure to run without security"));
  auto ring = load_key_ring(flags.keys);
  if (!ring) return std::unexpected("--keys: " + ring.error());
  return NetSecurity{std::move(*ring)};
}

}  // namespace rhot
