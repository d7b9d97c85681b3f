#pragma once
// rhot-eval nodes --chaos SECONDS: faults thrown at a running node network, many together, at
// random times from the seed (docs/camera-nodes.md, "Chaos"):
//   - a node killed (SIGKILL) and started again 0.3-2 s later, with a new clock (offset up to
//     +-50 ms, drift up to +-200 ppm) and a slow link (0-3 ms); one node down at a time;
//   - while a node is down, an impostor at its endpoint: a publisher with a key of its own (or none,
//     against an insecure master) sending frames of false markers, junk and oversized messages;
//   - all along, an attacker connecting to every node's control endpoint without a key, sending
//     junk and oversized requests;
//   - the master's receiving thread stalled for 50-300 ms at random times, and for 200-300 ms
//     0.1-0.2 s after every rejoin (while the node's clock is measured anew: a stall there once
//     put its frames an exposure off).
// The master's loop asks step() what to do now, tells on_frame() what it assembled, and asks
// all_up() whether every node was serving at an exposure.

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "tracking/net/ChildProcess.h"
#include "tracking/net/FrameAssembler.h"
#include "tracking/net/NodeSource.h"

namespace rhot::eval {

struct ChaosNode {
  std::vector<std::string> argv;  // as first started
  std::string endpoint;           // tcp://127.0.0.1:PORT (its control endpoint the port after)
  std::vector<int> cameras;
};

class Chaos {
 public:
  Chaos(unsigned seed, double seconds, std::vector<ChaosNode> nodes, std::vector<ChildProcess>& children, std::filesystem::path log,
        NodeSource& source, bool secure);
  ~Chaos();
  Chaos(const Chaos&) = delete;
  Chaos& operator=(const Chaos&) = delete;

  // The faults due at t_s (seconds from the run's start).
  void step(double t_s);
  // A frame the master assembled (t_s: now, seconds from the run's start).
  void on_frame(const AssembledFrame& frame, double t_s);
  // Whether every node was serving at t_s: none between its kill and its first frame after the
  // restart (its rejoin).
  bool all_up(double t_s) const;
  void report(nlohmann::json& j) const;

 private:
  struct Down {
    int node = 0;
    double killed_s = 0.0, restart_s = 0.0;
    std::optional<double> restarted_s, rejoined_s;
    std::optional<double> stall_s;  // the stall due after its rejoin (done: reset)
  };
  void stall(double min_s, double max_s);  // the master's receiving thread, for a time between the two
  void kill_one(double t_s);
  void restart(Down& d, double t_s);
  std::vector<std::string> new_clock_argv(const ChaosNode& node);

  std::mt19937_64 rng_;
  double seconds_;
  std::vector<ChaosNode> nodes_;
  std::vector<ChildProcess>& children_;
  std::filesystem::path log_;
  NodeSource& source_;
  bool secure_;
  double next_event_s_ = 2.0;
  std::vector<Down> downs_;
  int stalls_ = 0;
  double stalled_s_ = 0.0;
  struct Attacker;
  std::unique_ptr<Attacker> attacker_;
};

// The master's resident memory (kB, /proc/self/status VmRSS; 0 where unknown), and its heap in use
// (kB: what malloc has handed out and not had back; under AddressSanitizer its allocator's count,
// which leaves out the freed memory it holds in quarantine and so grows in RSS).
long resident_kb();
long heap_in_use_kb();

}  // namespace rhot::eval
