#include "engine/demo/DemoRuntime.h"

#include "engine/core/Transform.h"
#include "engine/render/StereoCamera.h"
#include "engine/scene/SceneLoader.h"

namespace rhot {

std::expected<std::unique_ptr<DemoRuntime>, std::string> DemoRuntime::create(const SceneDesc& scene, Renderer* renderer,
                                                                             DemoOptions options) {
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
  systems.add({"source", deps(after), {}, [this](World&, const FrameContext& f) {
                 advance(f);
                 if (advancing_) pipeline_->source(demo_time_s_);
               }});
  systems.add({"matching", {"source"}, {}, [this](World&, const FrameContext&) {
                 if (advancing_) pipeline_->matching();
               }});
  systems.add({"stars", {"matching"}, {}, [this](World& w, const FrameContext&) {
                 if (advancing_) pipeline_->stars(w);
               }});
  systems.add({"hands", {"stars"}, {}, [this](World&, const FrameContext&) {
                 if (advancing_) pipeline_->hands();
               }});
  systems.add({"transforms", {"hands"}, {}, [](World& w, const FrameContext&) { update_world_transforms(w); }});
  systems.add({"physics", {"transforms"}, {}, [this](World& w, const FrameContext&) {
                 if (!advancing_) return;
                 pipeline_->physics(w);
                 update_world_transforms(w);  // dynamic bodies moved; children follow
               }});
  if (renderer_) systems.add({"render", {"physics"}, {}, [this](World&, const FrameContext&) { render(); }});
}

void DemoRuntime::advance(const FrameContext& f) {
  // The demo's clock starts where the frame loop's does and moves one step per frame it runs.
  if (demo_frames_ == 0 && !advancing_started_) {
    next_time_s_ = f.time_s;
    advancing_started_ = true;
  }
  advancing_ = !paused_ || step_requested_;
  step_requested_ = false;
  if (!advancing_) return;
  demo_time_s_ = next_time_s_;
  next_time_s_ += f.dt_s;
  ++demo_frames_;
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
  fill_debug(debug_);
  const bool any_debug = !debug_.lines().empty() || !debug_.points().empty();
  FrameInput frame = scene_renderer_->build(world_, views_, hands, any_debug ? &debug_ : nullptr);
  if (overlay_ && renderer_->begin_overlay()) overlay_();
  renderer_->render(frame);
}

namespace {

glm::vec3 to_glm(const Eigen::Vector3d& v) { return {static_cast<float>(v.x()), static_cast<float>(v.y()), static_cast<float>(v.z())}; }

}  // namespace

void DemoRuntime::fill_debug(DebugDraw& debug) const {
  const DebugViews& v = options_.debug;
  const auto& points = pipeline_->points();
  if (v.markers) {
    for (const Eigen::Vector3d& p : points) debug.point(to_glm(p), 0.004f, {1.0f, 1.0f, 0.3f, 1.0f});
  }
  const CameraRig& rig = pipeline_->rig();
  if (v.rays) {
    const auto& cameras = pipeline_->point_cameras();
    for (std::size_t i = 0; i < points.size() && i < cameras.size(); ++i) {
      for (const int c : cameras[i]) {
        if (c < 0 || static_cast<std::size_t>(c) >= rig.cameras.size()) continue;
        debug.line(to_glm(rig.cameras[static_cast<std::size_t>(c)].centre_world()), to_glm(points[i]), {1.0f, 0.85f, 0.3f, 0.6f});
      }
    }
  }
  if (v.frusta) {
    for (const Camera& cam : rig.cameras) {
      const Rigid3d world_from_cam = cam.cam_from_world.inverse();
      Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
      m.topLeftCorner<3, 3>() = world_from_cam.rotation.toRotationMatrix();
      m.topRightCorner<3, 1>() = world_from_cam.translation;
      glm::mat4 g(1.0f);
      for (int r = 0; r < 4; ++r) {
        for (int c = 0; c < 4; ++c) g[c][r] = static_cast<float>(m(r, c));
      }
      const CameraIntrinsics& k = cam.intrinsics;
      debug.camera_frustum(g, k.width_px, k.height_px, static_cast<float>(k.fx), static_cast<float>(k.fy), static_cast<float>(k.cx),
                           static_cast<float>(k.cy), 0.25f, {0.3f, 0.9f, 1.0f, 1.0f});
    }
  }
  if (v.colliders) {
    for (const HandSide side : {HandSide::kLeft, HandSide::kRight}) {
      const HandColliders& colliders = pipeline_->hand_physics().hand(side);
      for (const HandColliders::Capsule& c : colliders.capsules()) {
        debug.capsule(to_glm(c.a_world), to_glm(c.b_world), static_cast<float>(c.radius_m),
                      c.soft ? glm::vec4(1.0f, 0.5f, 0.1f, 1.0f) : glm::vec4(0.2f, 0.9f, 0.9f, 1.0f));
      }
      // The tracked skeleton, where the physics is aiming the bones.
      const HandInput& in = pipeline_->hand_inputs()[side == HandSide::kLeft ? 0 : 1];
      if (!in.seen) continue;
      for (const HandBone& b : hand_bones()) {
        debug.line(to_glm(in.joints_world[static_cast<std::size_t>(b.from)]), to_glm(in.joints_world[static_cast<std::size_t>(b.to)]),
                   {1.0f, 0.2f, 0.8f, 1.0f});
      }
    }
  }
}

}  // namespace rhot
