#pragma once
// The runtime: a scene, a source of tracking results, physics and the stereo renderer, as
// declared, timed systems of the frame loop. It only runs: what feeds it (live cameras of any
// kind, the simulated rig, a recording) is decided by whoever builds it (tools/demo, rhot-eval,
// tests), through the ResultSource it is given. One frame:
//
//   clock       the runtime's clock advances one step (not while paused, unless stepping)
//   <tracking>  the result source's stages (live: source, matching, stars, hands; or replay)
//   tracked     tracking results into components: tracked objects' Transforms, hands' Hand, the
//               markers (engine/tracked/TrackedObjects.h)
//   record      with RuntimeSettings::record: the frame's results appended to a recording
//   stream      with RuntimeSettings::stream: the frame's results handed to the OSC stream
//               (engine/stream/OscStream.h: sent off the frame thread)
//   publish     with RuntimeSettings::publish_hands: the hands into shared memory for other
//               processes, such as rhot's OpenXR layer (engine/stream/HandShare.h)
//   transforms  world transforms of the hierarchy
//   physics     hand colliders, grasping, Bullet, interactions (reads Hand, writes HandBody)
//   render      both eyes, drawn from the components (with a renderer)
//
// An application adds stages of its own between these (add_stage): the demo's script looks where
// the cube lies after physics, for example. Stages other than transforms and render run only on
// frames the clock advances.

#include <array>
#include <cstdint>
#include <deque>
#include <map>
#include <expected>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "engine/core/Systems.h"
#include "engine/core/World.h"
#include "engine/interact/HandPhysics.h"
#include "engine/render/DebugDraw.h"
#include "engine/render/Renderer.h"
#include "engine/render/SceneRenderer.h"
#include "engine/runtime/Latency.h"
#include "engine/scene/SceneDesc.h"
#include "engine/hand/HandComponents.h"
#include "engine/tracked/ResultSource.h"
#include "engine/tracked/SessionRecorder.h"
#include "engine/tracked/TrackedObjects.h"
#include "engine/stream/HandShare.h"
#include "engine/stream/OscStream.h"

namespace rhot {

// What the debug views draw over the scene (toggled from the overlay, or set by flags).
struct DebugViews {
  bool markers = false;    // triangulated marker points as small spheres
  bool rays = false;       // from each camera that saw a point to the point
  bool frusta = false;     // each camera's viewing pyramid
  bool colliders = false;  // the hands' collider capsules (orange where held back) and the tracked skeleton
};

struct RuntimeSettings {
  std::filesystem::path star_set;  // the marker stars objects are tracked by (required when any is)
  std::filesystem::path record;    // write every frame's hands and tracked objects here (empty: no recording)
  std::string stream;              // send them to osc://HOST:PORT[,vmc] (empty: nowhere; OscStream.h)
  DebugViews debug;
  // Draw the hands where their tracked motion puts them at the frame's predicted display time
  // (engine/runtime/Latency.h); false: where they were tracked.
  bool predict = true;
  // Latency percentiles (and GPU times) are over this many of the last frames; memory grows with
  // it, about 40 bytes a frame.
  std::size_t latency_window_frames = 65536;
  // Publish every frame's hands for other processes on this machine (engine/stream/HandShare.h:
  // rhot's OpenXR layer reads them), in the shared memory hand_share_name() names. Where another
  // process is publishing there (or the block cannot be had), that is logged once, and the
  // runtime tries again once a second and takes over when it can.
  bool publish_hands = true;
  // The rig registered to a headset's STAGE space (rhot-calib headset), published with the hands.
  Rigid3d world_from_stage;
};

// A frame the headset has shown, once the GPU has finished it: its moments (Latency.h), and the
// tracked hands' joints as tracked and as predicted for its display time (what was drawn, before
// the physics hand's own adjustments), for measuring prediction against a truth.
struct DisplayedFrame {
  double t_s = 0.0;  // the runtime's clock of its tracking results
  FrameMoments moments;
  double predicted_display_s = 0.0;  // what the prediction aimed at (steady clock)
  double horizon_s = 0.0;            // how far ahead of capture the hands were moved (0: not predicted)
  std::array<bool, 2> seen{};        // 0 left, 1 right
  std::array<std::array<Eigen::Vector3d, kHandJointCount>, 2> tracked{};
  std::array<std::array<Eigen::Vector3d, kHandJointCount>, 2> predicted{};
  // The star-tracked objects seen in the frame, by star id: as tracked and as drawn (predicted).
  std::map<int, std::pair<Rigid3d, Rigid3d>> objects;
};

class Runtime {
 public:
  // Builds the result source once the scene is in the world and its tracked objects are known.
  using TrackingFactory = std::function<std::expected<std::unique_ptr<ResultSource>, std::string>(World&, const TrackedObjects&)>;

  // Instantiates `scene`, finds its star-tracked objects, asks `make_tracking` for the results'
  // source, builds the physics and the hand entities. `renderer` may be null (no render stage).
  // Fails, naming what is wrong, on a star set that cannot be read or lacks a tracked object's
  // star, the factory's errors, a physics error, or a recording that cannot be written.
  [[nodiscard]] static std::expected<std::unique_ptr<Runtime>, std::string> create(const SceneDesc& scene, Renderer* renderer,
                                                                                   const RuntimeSettings& settings,
                                                                                   const TrackingFactory& make_tracking);

  // A stage of the application's, run right after the stage named `after` on frames the clock
  // advances. Before add_systems. Stages added after the same one run in the order added.
  void add_stage(const std::string& after, TrackingStage stage);
  // Adds the runtime's systems; `after` names a system they run after ("" for none).
  void add_systems(Systems& systems, const std::string& after);
  // With a headset (the renderer's): handles its runtime's events and waits for its next frame
  // (xrWaitFrame), which paces the loop; while its session is not running, idles a few
  // milliseconds instead. Give it to FrameLoopSettings::pace so that the wait is not counted as
  // the frame's work; where a frame starts without it, the clock stage calls it. Nothing without a
  // headset. engine/runtime/HeadsetLoop.h sets the loop up and runs it so.
  void wait_for_headset();
  // Runs every stage once at t_s, as a frame the clock advances to t_s would, without a frame loop
  // (for tools and tests that drive the runtime themselves). The clock is not touched.
  void run_frame(double t_s);

  World& world() { return world_; }
  const SceneDesc& scene() const { return scene_; }
  Renderer* renderer() const { return renderer_; }
  ResultSource& tracking() { return *tracking_; }
  const TrackedObjects& objects() const { return objects_; }
  HandPhysics& physics() { return *physics_; }
  // A hand entity's components (there are always two hand entities).
  const Hand& hand(HandSide side);
  const HandBody* hand_body(HandSide side);

  // Pausing stops the clock: tracking and physics do nothing and the last state is drawn again.
  // step() runs the next frame while paused.
  void set_paused(bool paused) { paused_ = paused; }
  bool paused() const { return paused_; }
  void step() { step_requested_ = true; }
  double time_s() const { return time_s_; }
  std::uint64_t frames() const { return frames_; }

  DebugViews& debug_views() { return settings_.debug; }
  // Called in the render stage once the renderer's overlay frame has begun (Dear ImGui calls are
  // allowed); not called without an overlay.
  void set_overlay(std::function<void()> build_ui) { overlay_ = std::move(build_ui); }

  // The debug shapes the views in debug_views() draw for the current state (from components).
  void fill_debug(DebugDraw& debug);

  // Tracking, render and motion-to-photon latency of the frames displayed so far (with a
  // renderer; frames drawn while paused are not counted).
  const LatencyStats& latency() const { return latency_; }
  bool predicting() const { return settings_.predict; }
  // Adds a function called for each frame once it is displayed (one frame after it is drawn).
  void add_displayed_observer(std::function<void(const DisplayedFrame&)> observer) { displayed_observers_.push_back(std::move(observer)); }
  // The OSC stream's counts (RuntimeSettings::stream) once the frames handed over so far are sent;
  // nothing without one.
  std::optional<OscStream::Stats> stream_stats() const;
  // The GPU's time per eye of the displayed frames (with RendererSettings::gpu_timings): p50 and
  // p99 over the run; nothing without timings.
  std::optional<std::array<TimingSummary, 2>> gpu_eye_ms() const;

 private:
  struct Stage {
    TrackingStage stage;
    bool always = false;  // also on frames the clock does not advance
    bool added = false;   // by the application (add_stage)
  };
  Runtime() = default;
  struct PendingFrame {
    std::uint64_t renderer_frame = 0;
    DisplayedFrame shown;
  };
  void advance(const FrameContext& f);
  void render();
  void record();   // the "record" stage: this frame's tracking and grasps into the recording
  void publish();  // the "publish" stage: this frame's hands into the shared memory
  // Frames the renderer has finished since the last call: displayed, measured, observed.
  void collect_displayed();
  Entity hand_entity(HandSide side);

  SceneDesc scene_;
  World world_;
  RuntimeSettings settings_;
  TrackedObjects objects_;
  std::unique_ptr<ResultSource> tracking_;
  std::unique_ptr<HandPhysics> physics_;
  std::optional<SessionRecorder> recorder_;
  std::unique_ptr<OscStream> stream_;
  std::unique_ptr<HandShareWriter> hand_share_;  // while this runtime owns the block
  double hand_share_tried_s_ = -1e300;
  bool hand_share_warned_ = false;
  std::map<int, std::string> stream_names_;  // tracked objects' names by star id
  std::vector<Stage> stages_;
  Renderer* renderer_ = nullptr;
  std::unique_ptr<SceneRenderer> scene_renderer_;
  StereoViews views_;
  DebugDraw debug_;
  std::function<void()> overlay_;
  bool paused_ = false;
  bool step_requested_ = false;
  bool advancing_ = true;        // this frame runs tracking and physics
  bool headset_waited_ = false;  // wait_for_headset() ran for the coming frame
  bool started_ = false;
  double time_s_ = 0.0;  // of the frame that ran last
  double next_time_s_ = 0.0;
  std::uint64_t frames_ = 0;
  // Latency (Latency.h): steady-clock moments of the frame running now.
  double frame_start_s_ = 0.0;
  double pose_s_ = 0.0;
  std::optional<VsyncClock> vsync_;
  std::vector<MotionPredictor> hand_motion_;  // 0 left, 1 right: the tracked joints
  std::map<int, PoseMotion> object_motion_;   // by star id
  std::deque<double> recent_gpu_s_;           // submit to done of the last frames
  std::deque<PendingFrame> pending_;
  LatencyStats latency_;
  std::array<std::deque<double>, 2> gpu_eye_ms_;  // the last RuntimeSettings::latency_window_frames
  std::vector<std::function<void(const DisplayedFrame&)>> displayed_observers_;
};

}  // namespace rhot
