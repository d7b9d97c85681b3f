#pragma once
// Systems: named functions over the World that run once per frame in a declared order, each
// timed every frame (StereoKit-style named dependencies). A system names the systems it must run
// after (or before); among systems with no constraint between them, the order they were added is
// kept, so a frame is deterministic.

#include <chrono>
#include <cstdint>
#include <expected>
#include <functional>
#include <span>
#include <string>
#include <vector>

namespace rhot {

class World;

// What a system knows of the frame it runs in. Times are simulation times (fixed step).
struct FrameContext {
  std::uint64_t frame_index = 0;
  double dt_s = 0.0;    // fixed time step
  double time_s = 0.0;  // simulation time at the start of this frame
};

struct SystemDesc {
  std::string name;                 // unique; used in logs, statistics and dependencies
  std::vector<std::string> after;   // systems that must run before this one
  std::vector<std::string> before;  // systems that must run after this one
  std::function<void(World&, const FrameContext&)> run;
};

class Systems {
 public:
  // Adds a system. Precondition: its name is new and it has a function. The order is computed by
  // the next call to build().
  void add(SystemDesc system);

  // Orders the systems. Fails, naming the systems involved, on a dependency on an unknown system
  // or a dependency cycle; on failure the previous order stays in force.
  [[nodiscard]] std::expected<void, std::string> build();

  // Runs every system once in order, writing each one's wall time in milliseconds to
  // durations_ms (indexed like names()). Precondition: build() succeeded since the last add();
  // durations_ms.size() == size().
  void run(World& world, const FrameContext& frame, std::span<double> durations_ms);

  // System names in run order (after build()).
  const std::vector<std::string>& names() const { return ordered_names_; }
  std::size_t size() const { return systems_.size(); }

 private:
  std::vector<SystemDesc> systems_;  // in the order added
  std::vector<std::size_t> order_;   // indices into systems_, run order
  std::vector<std::string> ordered_names_;
  bool built_ = false;
};

}  // namespace rhot
