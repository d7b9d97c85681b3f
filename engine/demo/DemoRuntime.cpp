#include "engine/demo/DemoRuntime.h"

#include "engine/core/Transform.h"
#include "engine/render/StereoCamera.h"
#include "engine/scene/SceneLoader.h"

namespace rhot {

std::expected<std::unique_ptr<DemoRuntime>, std::string> DemoRuntime::create(const SceneDesc& scene, Renderer* renderer, DemoOptions options) {
  std::unique_ptr<DemoRuntime> d(new DemoRuntime());
  d->scene_ = scene;
  d->options_ = options;
  instantiate(d->scene_, d->world_);
  auto pipeline = Pipeline::create(d->world_, d->scene_, options.pipeline);
  if (!pipeline) return std::unexpected(pipeline.error());
  d->pipeline_ = std::move(*pipeline);
  d->renderer_ = renderer;
  if (renderer) {
    d->scene_renderer_ = std::make_unique<SceneRenderer>(*renderer);
    d->views_ = stereo_views(default_world_from_head(), scene.settings.headset);
  }
  return d;
}

void DemoRuntime::add_systems(Systems& systems, const std::string& after) {
  const auto deps = [&](const std::string& d) { return d.empty() ? std::vector<std::string>{} : std::vector<std::string>{d}; };
  systems.add({"source", deps(after), {}, [this](World&, const FrameContext& f) { pipeline_->source(f.time_s); }});
  systems.add({"matching", {"source"}, {}, [this](World&, const FrameContext&) { pipeline_->matching(); }});
  systems.add({"stars", {"matching"}, {}, [this](World& w, const FrameContext&) { pipeline_->stars(w); }});
  systems.add({"hands", {"stars"}, {}, [this](World&, const FrameContext&) { pipeline_->hands(); }});
  systems.add({"transforms", {"hands"}, {}, [](World& w, const FrameContext&) { update_world_transforms(w); }});
  systems.add({"physics", {"transforms"}, {}, [this](World& w, const FrameContext&) {
                 pipeline_->physics(w);
                 update_world_transforms(w);  // dynamic bodies moved; children follow
               }});
  if (renderer_) systems.add({"render", {"physics"}, {}, [this](World&, const FrameContext&) { render(); }});
}

void DemoRuntime::render() {
  std::vector<HandDrawInput> hands;
  for (const HandSide side : {HandSide::kLeft, HandSide::kRight}) {
    if ((side == HandSide::kLeft && !scene_.settings.left_hand) || (side == HandSide::kRight && !scene_.settings.right_hand)) continue;
    const HandColliders& colliders = pipeline_->hand_physics().hand(side);
    const HandInput& in = pipeline_->hand_inputs()[side == HandSide::kLeft ? 0 : 1];
    if (!in.seen) continue;
    const auto joints = colliders.active() ? colliders.physical_joints() : in.joints_world;
    HandDrawInput h;
    for (std::size_t j = 0; j < kHandJointCount; ++j) {
      h.joint_world[j] = glm::vec3(joints[j].cast<float>().x(), joints[j].cast<float>().y(), joints[j].cast<float>().z());
      h.radius_m[j] = static_cast<float>(in.radius_m[j]);
    }
    if (pipeline_->hand_physics().grasp().holding(side)) h.color = {0.55f, 0.85f, 0.55f, 1.0f};
    hands.push_back(h);
  }
  debug_.clear();
  if (options_.draw_points) {
    for (const Eigen::Vector3d& p : pipeline_->points()) debug_.point(glm::vec3(p.cast<float>().x(), p.cast<float>().y(), p.cast<float>().z()), 0.004f, {1.0f, 1.0f, 0.3f, 1.0f});
  }
  renderer_->render(scene_renderer_->build(world_, views_, hands, options_.draw_points ? &debug_ : nullptr));
}

}  // namespace rhot
