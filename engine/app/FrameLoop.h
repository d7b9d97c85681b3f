#pragma once
// The frame loop: a fixed time step (default 90 Hz, one headset frame), the systems run in their
// declared order each frame, and every frame timed into FrameStats. A frame that misses its
// budget is logged (at most once a second, with how many missed since the last warning).

#include <cstdint>
#include <expected>
#include <functional>
#include <string>
#include <vector>

#include "engine/app/FrameStats.h"
#include "engine/core/Systems.h"

namespace rhot {

class World;

struct FrameLoopSettings {
  double rate_hz = 90.0;    // simulation steps per second; dt = 1 / rate_hz
  double budget_ms = 11.1;  // a frame slower than this counts as a miss
  // Pace frames to the wall clock (a window or headset). Off: run frames back to back with the
  // same fixed dt, as headless runs and tests do, so results do not depend on machine speed.
  bool real_time = false;
  std::size_t stats_window_frames = 65536;
  // Called before each frame, outside its timing: what paces the loop from outside, such as a
  // headset runtime's wait for its next frame (Runtime::wait_for_headset).
  std::function<void()> pace;

  [[nodiscard]] std::expected<void, std::string> check() const;
};

class FrameLoop {
 public:
  // Preconditions: settings.check() passes; systems.build() succeeded. Both references must
  // outlive the loop.
  FrameLoop(World& world, Systems& systems, FrameLoopSettings settings);

  // Runs one frame (after settings.pace, if given).
  void step();

  // Runs frames until `frames` have run in this call (0: no limit) or keep_running (checked
  // before each frame, when given) returns false. Returns the number of frames run.
  std::uint64_t run(std::uint64_t frames, const std::function<bool()>& keep_running = {});

  std::uint64_t frame_index() const { return frame_index_; }  // frames run so far
  double time_s() const { return static_cast<double>(frame_index_) * dt_s_; }
  double dt_s() const { return dt_s_; }
  const FrameStats& stats() const { return stats_; }

 private:
  World& world_;
  Systems& systems_;
  FrameLoopSettings settings_;
  double dt_s_;
  FrameStats stats_;
  std::vector<double> stage_ms_;
  std::uint64_t frame_index_ = 0;
  double last_warning_s_ = -1e9;  // wall clock, seconds
  std::uint64_t misses_since_warning_ = 0;
};

}  // namespace rhot
