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

namespace rhot {

class World;

struct PipelineSettings {
  std::filesystem::path asset_dir;   // where the defaults below are found
  std::filesystem::path rig_file;    // empty: the scene's rig, else assets/rigs/seated-4.yaml
  std::filesystem::path star_set;    // empty: assets/stars/seed-case.json (the objects' stars)
  double sigma_px = 0.3;
  unsigned seed = 1;
  bool perfect_hands = false;  // physics gets the true hands, not the tracked ones (to tell tracking from physics)
  std::filesystem::path replay;  // play this recording instead of simulating cameras and tracking
  double speed = 1.0;            // replay speed (2: twice as fast)
  std::filesystem::path record;  // write every frame's hands and tracked objects here
};

struct PipelineCounts {
  std::size_t detections = 0;  // over all cameras
  std::size_t points = 0;      // triangulated
  double mean_reprojection_rms_px = 0.0;  // over the triangulated points
  int stars_seen = 0;          // objects' stars measured this frame
  std::vector<int> seen_star_ids;
  std::array<bool, 2> hands_seen{};
};

class Pipeline {
 public:
  // `world` holds `scene` instantiated. Fails on a missing rig, star set or hand layout, a
  // `tracked_by` star missing from the set, or a physics error.
  [[nodiscard]] static std::expected<std::unique_ptr<Pipeline>, std::string> create(World& world, const SceneDesc& scene,
                                                                                   PipelineSettings settings);

  void source(double t_s);
  void matching();
  void stars(World& world);
  void hands();
  void physics(World& world);

  const SceneTruth& truth() const { return truth_; }
  const PipelineCounts& counts() const { return counts_; }
  const std::array<HandInput, 2>& hand_inputs() const { return inputs_; }
  const TrackedHand& tracked_hand(HandSide side) const { return hand_trackers_[side == HandSide::kLeft ? 0 : 1]->last(); }
  HandPhysics& hand_physics() { return *physics_; }
  const std::vector<Eigen::Vector3d>& points() const { return points_; }
  // Per triangulated point: the cameras that saw it.
  const std::vector<std::vector<int>>& point_cameras() const { return point_cameras_; }
  // The last frame's detections per camera (empty when replaying).
  const RigFrame& frame() const { return frame_; }
  double speed() const { return settings_.speed; }
  // Replay speed from the next frame on (precondition: finite and > 0).
  void set_speed(double speed);
  const CameraRig& rig() const { return sim_->rig(); }
  const DemoScript& script() const { return script_; }
  bool replaying() const { return replay_.has_value(); }
  const Recording* replay() const { return replay_ ? &*replay_ : nullptr; }

 private:
  explicit Pipeline(const SceneDesc& scene) : script_(scene) {}
  PipelineSettings settings_;
  std::optional<Recording> replay_;
  RecordedFrame replayed_;
  std::optional<RecordingWriter> recorder_;
  std::map<std::string, Rigid3d> object_poses_;  // tracked objects by entity name, as last tracked
  std::map<int, std::string> name_of_star_;

  DemoScript script_;
  SceneTruth truth_;
  std::unique_ptr<SimulatedRig> sim_;
  RigFrame frame_;
  std::vector<Eigen::Vector3d> points_;
  std::vector<std::vector<int>> point_cameras_;
  std::unique_ptr<StarTracker> star_tracker_;
  std::map<int, Rigid3d> object_from_star_;          // by star id: where the star sits on its object
  std::vector<std::pair<Entity, int>> tracked_;       // entity, star id
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
