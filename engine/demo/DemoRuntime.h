#pragma once
// The demo's frame as systems of the frame loop, shared by rhot-demo and `rhot-eval frame`:
//
//   source -> matching -> stars -> hands -> transforms -> physics -> render
//
// (engine/pipeline/Pipeline.h for the first five, then the stereo renderer). Each system is timed
// by the frame loop, so the frame statistics carry every stage. The hands are drawn where the
// physics has them (the "ghost hand": fingers rest on surfaces instead of sinking in), green while
// they hold something.

#include <cstdint>
#include <expected>
#include <functional>
#include <memory>
#include <string>

#include "engine/core/Systems.h"
#include "engine/core/World.h"
#include "engine/pipeline/Pipeline.h"
#include "engine/render/DebugDraw.h"
#include "engine/render/Renderer.h"
#include "engine/render/SceneRenderer.h"
#include "engine/scene/SceneDesc.h"

namespace rhot {

// What the debug views draw over the scene (toggled from the overlay, or set by flags).
struct DebugViews {
  bool markers = false;    // triangulated marker points as small spheres
  bool rays = false;       // from each camera that saw a point to the point
  bool frusta = false;     // each camera's viewing pyramid
  bool colliders = false;  // the hands' collider capsules (orange where held back) and the tracked skeleton
};

struct DemoOptions {
  PipelineSettings pipeline;
  DebugViews debug;
};

class DemoRuntime {
 public:
  // `renderer` may be null (no render stage). Fails naming what is wrong (rig, stars, layouts,
  // physics).
  [[nodiscard]] static std::expected<std::unique_ptr<DemoRuntime>, std::string> create(const SceneDesc& scene, Renderer* renderer,
                                                                                       DemoOptions options);

  // Adds the demo's systems; `after` names a system they run after ("" for none).
  void add_systems(Systems& systems, const std::string& after);

  World& world() { return world_; }
  Pipeline& pipeline() { return *pipeline_; }
  const SceneDesc& scene() const { return scene_; }

  // Pausing stops the demo's clock: source to physics do nothing and the last state is drawn
  // again. step() runs the next frame while paused.
  void set_paused(bool paused) { paused_ = paused; }
  bool paused() const { return paused_; }
  void step() { step_requested_ = true; }
  double demo_time_s() const { return demo_time_s_; }
  std::uint64_t demo_frames() const { return demo_frames_; }

  DebugViews& debug_views() { return options_.debug; }
  // Called in the render stage once the renderer's overlay frame has begun (Dear ImGui calls are
  // allowed); not called without an overlay.
  void set_overlay(std::function<void()> build_ui) { overlay_ = std::move(build_ui); }

  // The debug shapes the views in debug_views() draw for the current state.
  void fill_debug(DebugDraw& debug) const;

 private:
  DemoRuntime() = default;
  void render();
  void advance(const FrameContext& f);

  SceneDesc scene_;
  World world_;
  std::unique_ptr<Pipeline> pipeline_;
  Renderer* renderer_ = nullptr;
  std::unique_ptr<SceneRenderer> scene_renderer_;
  StereoViews views_;
  DemoOptions options_;
  DebugDraw debug_;
  std::function<void()> overlay_;
  bool paused_ = false;
  bool step_requested_ = false;
  bool advancing_ = true;  // this frame runs source to physics
  bool advancing_started_ = false;
  double demo_time_s_ = 0.0;  // of the frame that ran last
  double next_time_s_ = 0.0;
  std::uint64_t demo_frames_ = 0;
};

}  // namespace rhot
