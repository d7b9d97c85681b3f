#pragma once
// Recordings of tracked sessions (seed 000 section 9): every frame's hands (26 joints each, with
// radii and confidences) and star-tracked objects' poses, with timestamps, so a session can be
// played back at any speed, inspected, or converted to glTF (tools/gltf); played back as tracking results by ReplaySource.h.
//
// Format: JSON Lines (docs/recording-format.md). The first line is a header:
//   {"format": "rhot-recording", "version": 1, "rate_hz": 90, "joints": [26 OpenXR joint names],
//    "objects": ["tracked-mug", ...]}
// then one line per frame:
//   {"t": 0.0111, "hands": [{"side": "left", "seen": true, "wrist_pose": [x, y, z, qx, qy, qz, qw],
//     "joints": [[x, y, z] x 26], "radius": [26], "confidence": [26]}, {...right...}],
//    "objects": {"tracked-mug": [x, y, z, qx, qy, qz, qw], ...},
//    "holding": ["", "cube-red"], "grasp_events": [{"type": "grasp", "hand": "right", ...}]}
// Metres, seconds, quaternions (x, y, z, w) as glTF writes them.

#include <array>
#include <expected>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "engine/hand/HandInput.h"
#include "tracking/core/Rigid3.h"

namespace rhot {

// A grasp or release of the frame, as the physics raised it (engine/interact/GraspSystem.h).
struct RecordedGraspEvent {
  std::string type;    // "grasp" or "release"
  std::string hand;    // "left" or "right"
  std::string object;  // the entity's name
  std::string reason;  // why (InteractionEvent::reason)
  bool operator==(const RecordedGraspEvent&) const = default;
};

struct RecordedFrame {
  double t_s = 0.0;
  std::array<HandInput, 2> hands;  // 0 left, 1 right
  std::map<std::string, Rigid3d> objects;
  // What each hand held after the frame's physics ("" for nothing), and its grasps and releases:
  // empty in recordings made without the physics (and in version 1 files, which lack them).
  std::array<std::string, 2> holding;
  std::vector<RecordedGraspEvent> grasp_events;
};

struct Recording {
  double rate_hz = 90.0;
  std::vector<std::string> objects;
  std::vector<RecordedFrame> frames;  // increasing t_s
  // What load_recording read past, one sentence each naming the file and line (also logged as
  // warnings): a last frame cut short by a crash.
  std::vector<std::string> warnings;

  double duration_s() const { return frames.empty() ? 0.0 : frames.back().t_s - frames.front().t_s; }
  // The state at time t (from the first frame's time): joints and positions interpolated
  // linearly, rotations by slerp; confidence and "seen" from the nearer frame. Clamped at both ends.
  RecordedFrame at(double t_s) const;
};

// Every line read and checked; an error names the file, the line and the field. The one exception is
// a last line cut short, as a crash while a frame is written leaves it (no newline, not JSON): it is
// left out with a warning (Recording::warnings), so a crash loses at most that frame. A bad line
// anywhere else, or a last line that is whole JSON but not a frame, is an error.
[[nodiscard]] std::expected<Recording, std::string> load_recording(const std::filesystem::path& file);

class RecordingWriter {
 public:
  [[nodiscard]] static std::expected<RecordingWriter, std::string> open(const std::filesystem::path& file, double rate_hz,
                                                                        std::vector<std::string> objects);
  // Appends one frame (written and flushed at once, so a crash loses at most that frame).
  [[nodiscard]] std::expected<void, std::string> write(const RecordedFrame& frame);

 private:
  std::filesystem::path file_;
  std::unique_ptr<std::ofstream> out_;
};

}  // namespace rhot
