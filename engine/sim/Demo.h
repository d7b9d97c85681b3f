#pragma once
// The demo: the runtime launched (engine/launch/Launch.h) on the source the settings name, with
// the simulated rig as the source of its own when they name none, and the demo's own stages. Shared by rhot-demo, `rhot-eval frame`,
// rhot-simvideo and the tests.
//
// Sources:
//   simulated (default)  the simulated camera rig (tracking/sim) photographs the demo script's
//                        hands and star-tracked objects (DemoWorld below), with pixel noise and
//                        the hands' bones hiding markers; live tracking recovers them
//   video devices        one OpenCV capture per rig camera (tracking/source/VideoSource.h); no
//                        truth, and the demo ends with the stream
//   replay               a recording's tracking results (engine/tracked/ReplaySource.h)
//   camera nodes         rhot-node processes sending detections over ZeroMQ
//                        (tracking/net/NodeSource.h); no truth on this side
//
// Stages the demo adds to the runtime (simulated source only):
//   perfect-hands  after the tracking stages: the hands are the script's true hands (to tell
//                  tracking from physics)
//   look           after physics: the script's right hand aims its next pickup where the cube
//                  lies (DemoScript::reaim), as a user looks before reaching

#include <array>
#include <expected>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "engine/launch/Launch.h"
#include "engine/runtime/Runtime.h"
#include "engine/sim/ColourCameras.h"
#include "engine/sim/DemoScript.h"
#include "engine/tracked/LiveTracking.h"
#include "tracking/detect/BlobDetector.h"
#include "tracking/hand/HandLayout.h"
#include "tracking/rigid/StarIdentification.h"
#include "tracking/sim/Realism.h"
#include "tracking/sim/SimulatedWorld.h"

namespace rhot {

// The demo's settings: how to launch the runtime (engine/launch/Launch.h: rig, stars, replay,
// video devices, camera nodes, recording, streaming) and, for the simulated source, its world.
struct DemoSettings : LaunchSettings {
  double sigma_px = 0.3;  // the simulated cameras' pixel noise (overrides world.sigma_px)
  WorldSettings world;    // the rest of the simulated world (tracking/sim/Realism.h)
  unsigned seed = 1;
  bool perfect_hands = false;  // physics gets the true hands, not the tracked ones
  // Simulated colour cameras drawn by the renderer (ColourCameras) with colour_markers, on the
  // rig (default assets/rigs/stereo-640.yaml).
  ColourCameraSettings colour_cameras;

  // Every value a user can set checked: "<name>: <what is wrong>" for the first bad one.
  [[nodiscard]] std::expected<void, std::string> check() const;
};

// The demo script's world as the simulated rig sees it: both hands' markers (their layouts on the
// script's hands) and the tracked objects' star markers, with the hands' bones as occluders.
class DemoWorld final : public SimulatedWorld {
 public:
  // independent_hands_seed: 0 for the script's hands as they are, else each hand's bones scaled as
  // a user's own (tracking/sim/Realism.h, independent_hand) from this seed.
  DemoWorld(const DemoScript& script, const std::array<HandLayout, 2>& layouts, const TrackedObjects& objects,
            unsigned independent_hands_seed = 0);
  WorldSnapshot at(double t_s) override;
  // The truth at any moment (the script's, with the users' own hands), touching nothing.
  SceneTruth truth_at(double t_s) const;
  // What colour cameras photograph of a snapshot at() gave (its markers in its order): the hands
  // of the truth at that moment, each marker with its layout's colour and size, the objects'
  // star markers blue (kStarColour) and 14 mm across.
  ColourShot colour_shot(const WorldSnapshot& snapshot) const;
  static constexpr int kStarColour = 5;  // blue (tracking/core/MarkerColour.h)
  // The truth at the time last asked for (with unsynchronised cameras, the last camera's moment).
  const std::optional<SceneTruth>& truth() const { return truth_; }
  // The scene's bodies hide markers too (WorldSettings::occluding_bodies, the realistic world): from
  // now on every entity of `world` with a box, sphere or capsule mesh and a physics body (the table,
  // the objects, a door, a drawer) is an occluder where the world has it (WorldTransform) when a
  // snapshot is taken, a star-tracked object where the truth has it. Planes (the floor) and glTF
  // meshes hide nothing. `world` must outlive this.
  void hide_behind_bodies(World& world) { bodies_ = &world; }
  // The occluders hide_behind_bodies adds at the truth last asked for (empty without it).
  std::vector<Occluder> body_occluders() const;

 private:
  const DemoScript& script_;
  std::array<HandLayout, 2> layouts_;
  unsigned hands_seed_ = 0;
  struct Star {
    int id;
    Rigid3d object_from_star;
    std::array<Eigen::Vector3d, 4> markers_m;  // star frame
  };
  std::vector<Star> stars_;
  std::optional<SceneTruth> truth_;
  World* bodies_ = nullptr;
};

// The demo's simulated world on its own, without a runtime: what a camera node simulating the
// demo's cameras photographs, and what an evaluation compares with.
struct DemoSimulation {
  std::unique_ptr<DemoScript> script;  // the world reads it: keep both together
  std::array<HandLayout, 2> layouts;   // left, right
  TrackedObjects objects;
  std::shared_ptr<DemoWorld> world;
};
// The scene's script, the demo's hand layouts (assets/hands/low-cost-*.json, checked against each
// other and the objects' stars) and its star-tracked objects (from star_set, empty: the seed-case
// set). Fails naming the file or the clash.
[[nodiscard]] std::expected<DemoSimulation, std::string> make_demo_simulation(const SceneDesc& scene,
                                                                              const std::filesystem::path& asset_dir,
                                                                              const std::filesystem::path& star_set = {},
                                                                              unsigned independent_hands_seed = 0,
                                                                              bool colour_markers = false);

// How well the drawn hands match the true ones (simulated source with a renderer): per joint of a
// seen hand in each displayed frame, its distance from the truth at the frame's capture time
// (tracking error), and, at the frame's display time, of the joint as predicted and as tracked.
struct PredictionErrors {
  std::uint64_t joints = 0;
  double at_capture_sum_m = 0.0;
  double predicted_at_display_sum_m = 0.0;
  double tracked_at_display_sum_m = 0.0;
  double horizon_sum_s = 0.0;  // per joint, how far ahead it was predicted
  // The star-tracked objects' origins likewise, per object per displayed frame.
  std::uint64_t objects = 0;
  double object_at_capture_sum_m = 0.0;
  double object_predicted_at_display_sum_m = 0.0;
  double object_tracked_at_display_sum_m = 0.0;
  double at_capture_mean_m() const { return joints > 0 ? at_capture_sum_m / static_cast<double>(joints) : 0.0; }
  double predicted_at_display_mean_m() const { return joints > 0 ? predicted_at_display_sum_m / static_cast<double>(joints) : 0.0; }
  double tracked_at_display_mean_m() const { return joints > 0 ? tracked_at_display_sum_m / static_cast<double>(joints) : 0.0; }
  // The error at display time over the error at capture time: with prediction (what was drawn),
  // and without (had the tracked hand been drawn).
  double ratio() const { return at_capture_sum_m > 0.0 ? predicted_at_display_sum_m / at_capture_sum_m : 0.0; }
  double ratio_without_prediction() const { return at_capture_sum_m > 0.0 ? tracked_at_display_sum_m / at_capture_sum_m : 0.0; }
};

class Demo {
 public:
  // Its stages capture it: it stays where it was made.
  Demo(const Demo&) = delete;
  Demo& operator=(const Demo&) = delete;

  // Fails naming what is wrong: bad settings, a rig, star set or hand layout that cannot be read,
  // hand stars that share a face with each other or with an object's star (check_hand_stars),
  // video devices that cannot be opened or do not fit the rig, a recording that cannot be read or
  // written, a physics error; video with perfect hands or with a replay.
  [[nodiscard]] static std::expected<std::unique_ptr<Demo>, std::string> create(const SceneDesc& scene, Renderer* renderer,
                                                                                DemoSettings settings);

  Runtime& runtime() { return launch_->runtime(); }
  World& world() { return launch_->runtime().world(); }
  // Live tracking, unless replaying.
  LiveTracking* live() { return launch_->live(); }
  // The simulated world, when the source is the simulated rig.
  const DemoWorld* simulated() const { return world_.get(); }
  const DemoScript& script() const { return *script_; }
  // The drawn hands against the truth so far (nothing without the simulated source and a renderer).
  const PredictionErrors& prediction_errors() const { return prediction_errors_; }

 private:
  Demo() = default;
  // With the simulated source: perfect hands, the prediction errors' observer, the look stage.
  void add_stages(const DemoSettings& settings);
  std::unique_ptr<DemoScript> script_;  // before the runtime: its world reads the script
  std::shared_ptr<DemoWorld> world_;
  std::unique_ptr<Launch> launch_;
  PredictionErrors prediction_errors_;
};

}  // namespace rhot
