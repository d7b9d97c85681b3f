#pragma once
// One frame of rhot, tracking to physics (the renderer draws what it leaves in the world):
//
//   source    the simulated camera rig photographs the true hands' and objects' markers
//             (DemoScript), with pixel noise, the hands' bones hiding markers
//   matching  detections matched across cameras and triangulated
//   stars     objects' marker stars identified and tracked; each entity tracked by a star
//             (`tracked_by`) gets the tracked pose in its Transform
//   hands     each hand's star and fingertip markers -> a 26-joint hand (HandTracker)
//   physics   hand colliders, grasping, Bullet (HandPhysics)
//
// With video devices (PipelineSettings::video_devices), source reads one image per camera of the
// rig from OpenCV captures and detects their blobs (tracking/source/VideoSource.h) instead of
// simulating; there is no ground truth then (truth() is empty), and source_ended() turns true when
// the stream is over.
//
// Replaying a recording (PipelineSettings::replay), source reads the recorded frame instead and
// matching does nothing; stars and hands take the recorded poses. Recording
// (PipelineSettings::record) writes each frame's hands and tracked objects as the hands stage ends.
//
// Each stage is a separate call so the frame loop can time it.

#include <array>
#include <expected>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "engine/core/Entity.h"
#include "engine/physics/HandPhysics.h"
#include "engine/pipeline/DemoScript.h"
#include "engine/pipeline/Recording.h"
#include "engine/scene/SceneDesc.h"
#include "tracking/camera/Camera.h"
#include "tracking/hand/HandTracker.h"
#include "tracking/rigid/StarTracker.h"
#include "tracking/source/SimulatedRig.h"
#include "tracking/source/VideoSource.h"

namespace rhot {

class World;

struct PipelineSettings {
  std::filesystem::path asset_dir;  // where the defaults below are found
  std::filesystem::path rig_file;   // empty: the scene's rig, else assets/rigs/seated-4.yaml
  std::filesystem::path star_set;   // empty: assets/stars/seed-case.json (the objects' stars)
  double sigma_px = 0.3;
  unsigned seed = 1;
  // 1-euro filtering of each hand's frame and fingertips before the IK (HandTrackerSettings):
  // steadier hands at rest, some lag in fast moves. Off by default (docs/tracking.md).
  bool filter_hands = false;
  bool perfect_hands = false;    // physics gets the true hands, not the tracked ones (to tell tracking from physics)
  std::filesystem::path replay;  // play this recording instead of simulating cameras and tracking
  double speed = 1.0;            // replay speed (2: twice as fast)
  std::filesystem::path record;  // write every frame's hands and tracked objects here
  // Real cameras instead of the simulated rig: one OpenCV device per rig camera, in rig order (an
  // index such as "0", a video file, or an image sequence such as "cams/cam0_%04d.png").
  std::vector<std::string> video_devices;
  BlobDetectorSettings detector;  // for video_devices
};

struct PipelineCounts {
  std::size_t detections = 0;             // over all cameras
  std::size_t points = 0;                 // triangulated
  double mean_reprojection_rms_px = 0.0;  // over the triangulated points
  int stars_seen = 0;                     // objects' stars measured this frame
  std::vector<int> seen_star_ids;
  std::array<bool, 2> hands_seen{};
};

class Pipeline {
 public:
  // `world` holds `scene` instantiated. Fails on a missing rig, star set or hand layout, a
  // `tracked_by` star missing from the set, a physics error, or video devices that cannot be
  // opened or do not fit the rig (VideoSource::open), or video with perfect_hands or replay.
  [[nodiscard]] static std::expected<std::unique_ptr<Pipeline>, std::string> create(World& world, const SceneDesc& scene,
                                                                                    PipelineSettings settings);

  void source(double t_s);
  void matching();
  void stars(World& world);
  void hands();
  void physics(World& world);

  // The script's true hands and objects this frame; empty with video devices (no truth) and in replay.
  const std::optional<SceneTruth>& truth() const { return truth_; }
  // This frame's camera detections (empty in replay).
  const RigFrame& frame() const { return frame_; }
  // Whether the video stream is over (never for the simulated rig or a replay).
  bool source_ended() const { return source_ended_; }
  const VideoSource* video() const { return video_ ? &*video_ : nullptr; }
  const PipelineCounts& counts() const { return counts_; }
  const std::array<HandInput, 2>& hand_inputs() const { return inputs_; }
  const TrackedHand& tracked_hand(HandSide side) const { return hand_trackers_[side == HandSide::kLeft ? 0 : 1]->last(); }
  HandPhysics& hand_physics() { return *physics_; }
  const std::vector<Eigen::Vector3d>& points() const { return points_; }
  // Per triangulated point: the cameras that saw it.
  const std::vector<std::vector<int>>& point_cameras() const { return point_cameras_; }
  double speed() const { return settings_.speed; }
  // Replay speed from the next frame on (precondition: finite and > 0).
  void set_speed(double speed);
  const CameraRig& rig() const { return rig_; }
  const DemoScript& script() const { return script_; }
  bool replaying() const { return replay_.has_value(); }
  const Recording* replay() const { return replay_ ? &*replay_ : nullptr; }

 private:
  explicit Pipeline(const SceneDesc& scene) : script_(scene) {}
  void read_video();
  PipelineSettings settings_;
  std::optional<Recording> replay_;
  RecordedFrame replayed_;
  std::optional<RecordingWriter> recorder_;
  std::map<std::string, Rigid3d> object_poses_;  // tracked objects by entity name, as last tracked
  std::map<int, std::string> name_of_star_;

  DemoScript script_;
  std::optional<SceneTruth> truth_;
  CameraRig rig_;
  std::unique_ptr<SimulatedRig> sim_;  // the source, unless video_
  std::optional<VideoSource> video_;
  std::vector<VideoCameraStats> video_logged_;  // the counts last logged, per camera
  bool source_ended_ = false;
  RigFrame frame_;
  std::vector<Eigen::Vector3d> points_;
  std::vector<std::vector<int>> point_cameras_;
  std::unique_ptr<StarTracker> star_tracker_;
  std::map<int, Rigid3d> object_from_star_;      // by star id: where the star sits on its object
  std::vector<std::pair<Entity, int>> tracked_;  // entity, star id
  std::array<HandLayout, 2> layouts_;
  std::array<std::unique_ptr<HandTracker>, 2> hand_trackers_;
  std::array<HandInput, 2> inputs_;
  std::unique_ptr<HandPhysics> physics_;
  PipelineCounts counts_;
  double time_s_ = 0.0;
  double replay_clock_s_ = 0.0;
  double replay_last_t_s_ = 0.0;
  bool replay_started_ = false;
};

}  // namespace rhot
