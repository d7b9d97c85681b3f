#pragma once
// The demo's frame as systems of the frame loop, shared by rhot-demo and `rhot-eval frame`:
//
//   source -> matching -> stars -> hands -> transforms -> physics -> render
//
// (engine/pipeline/Pipeline.h for the first five, then the stereo renderer). Each system is timed
// by the frame loop, so the frame statistics carry every stage. The hands are drawn where the
// physics has them (the "ghost hand": fingers rest on surfaces instead of sinking in), green while
// they hold something.

#include <expected>
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

struct DemoOptions {
  PipelineSettings pipeline;
  bool draw_points = false;  // triangulated marker points as small spheres
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

 private:
  DemoRuntime() = default;
  void render();

  SceneDesc scene_;
  World world_;
  std::unique_ptr<Pipeline> pipeline_;
  Renderer* renderer_ = nullptr;
  std::unique_ptr<SceneRenderer> scene_renderer_;
  StereoViews views_;
  DemoOptions options_;
  DebugDraw debug_;
};

}  // namespace rhot
