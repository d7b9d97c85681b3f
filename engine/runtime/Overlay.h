#pragma once
// The runtime's Dear ImGui overlay in the desktop window:
//
//   frame     the whole frame's time over the last 3 s against the budget line; p50, p99, misses
//   stages    each stage's time last frame, p50 and p99
//   tracking  detections per camera, triangulated points and their reprojection RMS, marker stars
//             identified, each hand seen and its joints' mean confidence, pinch and grip
//   grasp     what each hand holds and the last interaction events
//   controls  pause (Space) and step (Right arrow or N) the demo's clock, replay speed, and the
//             debug views (markers, rays from cameras, camera frusta, hand colliders)
//
// build() makes the Dear ImGui calls of one frame; Runtime calls it once the renderer's
// overlay frame has begun.

#include <cstdint>
#include <array>
#include <deque>
#include <string>

#include "engine/app/FrameStats.h"
#include "engine/runtime/Runtime.h"

namespace rhot {

struct OverlayInfo {
  std::string scene;   // the scene file
  std::string source;  // "sim", "replay:FILE", ...
  std::string device;  // the Vulkan device (and how it shades)
  int eye_width_px = 0;
  int eye_height_px = 0;
};

class Overlay {
 public:
  // Both references must outlive the overlay.
  Overlay(Runtime& demo, const FrameStats& stats, OverlayInfo info) : demo_(demo), stats_(stats), info_(std::move(info)) {}

  void build();

 private:
  void frame_panel();
  void tracking_panel();
  void grasp_panel();
  void controls_panel();
  std::string object_name(Entity e) const;

  Runtime& demo_;
  const FrameStats& stats_;
  OverlayInfo info_;
  std::deque<std::string> events_;  // newest first
  std::uint64_t events_frame_ = ~0ull;
  // Latency percentiles, recomputed twice a second (they sort the run's window).
  std::array<TimingSummary, 3> latency_{};  // tracking, render, motion-to-photon
  std::uint64_t latency_frames_ = 0;
};

}  // namespace rhot
