#pragma once
// Multi-camera frames from single-camera messages that arrive in any order, late, twice, or not at
// all (the master's half of docs/camera-nodes.md, without the sockets, so it can be tested alone).
//
// Every message has its capture time already on the master's clock. The pending messages form
// groups: the oldest pending capture time opens a group, and each camera's first message within
// `tolerance_ns` of it belongs to it. A group closes
//   - when every camera that is waited for is in it, or is known to have nothing for it (its next
//     message is already past the group), or
//   - at its deadline, capture time + deadline_ns, with whatever arrived.
// So a silent or slow camera never holds a frame longer than the deadline. What comes for a
// group already closed is late; a camera's frame counter seen before is a duplicate; a counter
// lower than the camera's latest, with an older capture time, is out of order. All three are
// dropped and counted. A lower counter with a newer capture time means the node restarted: the
// camera's counters begin again.

#include <cstdint>
#include <deque>
#include <optional>
#include <vector>

#include "tracking/core/Frames.h"

namespace rhot {

struct AssemblySettings {
  std::int64_t tolerance_ns = 4'000'000;  // a group's span of capture times
  std::int64_t deadline_ns = 10'000'000;  // how long after its capture a group waits for stragglers
};

struct CameraMessage {
  int camera = 0;  // the rig's camera
  std::uint64_t counter = 0;
  std::int64_t capture_ns = 0;  // master clock
  std::int64_t arrival_ns = 0;  // master clock
  std::int64_t decode_ns = 0;   // the master's time spent decoding and converting it
  std::vector<Detection> detections;
};

struct AssembledFrame {
  std::int64_t capture_ns = 0;                        // the group's earliest capture time
  std::int64_t closed_ns = 0;                         // when it closed (master clock)
  std::int64_t close_cpu_ns = 0;                      // the master's time spent closing it (set by NodeSource)
  std::vector<std::optional<CameraMessage>> cameras;  // per rig camera; empty where none came
  int cameras_present() const;
};

struct AssemblyCounts {
  std::uint64_t messages = 0;
  std::uint64_t late = 0;
  std::uint64_t duplicates = 0;
  std::uint64_t out_of_order = 0;
  std::uint64_t restarts = 0;         // a camera's counter began again with newer captures (its node restarted)
  std::uint64_t frames = 0;           // groups closed
  std::uint64_t complete_frames = 0;  // closed with every camera waited for
  std::uint64_t deadline_frames = 0;  // closed by their deadline
};

class FrameAssembler {
 public:
  FrameAssembler(int cameras, AssemblySettings settings = {});

  // A camera's message. Returns false when it was dropped (late, duplicate, out of order, or a
  // camera outside the rig).
  bool add(CameraMessage message);
  // Every group that can close at master time now, oldest first. waited_for[c]: whether camera c
  // is expected at all (false for a lost node's cameras).
  std::vector<AssembledFrame> close(std::int64_t now_ns, const std::vector<bool>& waited_for);
  // The earliest deadline among the pending groups (nothing pending: none).
  std::optional<std::int64_t> next_deadline() const;
  // Forgets a camera's counters, for a node that restarted (its counters begin again at 0).
  void restart_camera(int camera);

  const AssemblyCounts& counts() const { return counts_; }

 private:
  int cameras_;
  AssemblySettings settings_;
  static constexpr std::size_t kRecentCounters = 64;
  std::deque<CameraMessage> pending_;              // by capture time
  std::vector<std::deque<std::uint64_t>> recent_;  // per camera: its latest counters, oldest first
  std::vector<std::optional<std::int64_t>> last_capture_ns_;
  std::optional<std::int64_t> closed_until_ns_;  // the latest closed group's window end
  AssemblyCounts counts_;
};

}  // namespace rhot
