#include "engine/runtime/Runtime.h"

#include <algorithm>

#include "base/Check.h"
#include "engine/core/Transform.h"
#include "engine/math/EigenGlm.h"
#include "engine/render/StereoCamera.h"
#include "engine/scene/SceneLoader.h"
#include "tracking/rigid/StarSet.h"

namespace rhot {

std::expected<std::unique_ptr<Runtime>, std::string> Runtime::create(const SceneDesc& scene, Renderer* renderer,
                                                                     const RuntimeSettings& settings,
                                                                     const TrackingFactory& make_tracking) {
  std::unique_ptr<Runtime> r(new Runtime());
  r->scene_ = scene;
  r->settings_ = settings;
  instantiate(r->scene_, r->world_);
  StarSet set;
  if (r->world_.view<TrackedBy>().size_hint() > 0) {
    auto loaded = load_star_set(settings.star_set);
    if (!loaded) return std::unexpected(loaded.error());
    set = std::move(*loaded);
  }
  auto objects = find_tracked_objects(r->world_, set, settings.star_set);
  if (!objects) return std::unexpected(objects.error());
  r->objects_ = std::move(*objects);
  auto tracking = make_tracking(r->world_, r->objects_);
  if (!tracking) return std::unexpected(tracking.error());
  r->tracking_ = std::move(*tracking);
  auto physics = HandPhysics::create(r->world_, r->scene_);
  if (!physics) return std::unexpected(physics.error());
  r->physics_ = std::move(*physics);
  create_tracking_entities(r->world_, r->scene_.settings, r->tracking_->rig());
  if (!settings.record.empty()) {
    auto recorder = SessionRecorder::open(settings.record, r->scene_.settings.headset.refresh_hz, r->objects_);
    if (!recorder) return std::unexpected(recorder.error());
    r->recorder_ = std::move(*recorder);
  }

  Runtime* self = r.get();
  for (TrackingStage& s : r->tracking_->stages()) r->stages_.push_back({std::move(s), false});
  r->stages_.push_back({{"tracked", [self](double) { apply_tracking_results(self->world_, self->tracking_->results(), self->objects_); }}});
  if (r->recorder_) r->stages_.push_back({{"record", [self](double) { self->recorder_->record(self->tracking_->results()); }}});
  r->stages_.push_back({{"transforms", [self](double) { update_world_transforms(self->world_); }}, true});
  r->stages_.push_back({{"physics", [self](double) {
                           self->physics_->step(self->world_);
                           update_world_transforms(self->world_);  // dynamic bodies moved; children follow
                         }}});
  r->renderer_ = renderer;
  if (renderer) {
    r->scene_renderer_ = std::make_unique<SceneRenderer>(*renderer);
    r->views_ = stereo_views(default_world_from_head(), scene.settings.headset);
    r->stages_.push_back({{"render", [self](double) { self->render(); }}, true});
  }
  return r;
}

void Runtime::add_stage(const std::string& after, TrackingStage stage) {
  auto at = std::find_if(stages_.begin(), stages_.end(), [&](const Stage& s) { return s.stage.name == after; });
  RHOT_PRECONDITION(at != stages_.end(), "Runtime::add_stage: no stage named " + after);
  ++at;
  while (at != stages_.end() && at->added) ++at;  // behind the application's stages already there
  stages_.insert(at, {std::move(stage), false, true});
}

void Runtime::add_systems(Systems& systems, const std::string& after) {
  std::vector<std::string> deps;
  if (!after.empty()) deps.push_back(after);
  systems.add({"clock", deps, {}, [this](World&, const FrameContext& f) { advance(f); }});
  std::string previous = "clock";
  for (const Stage& s : stages_) {
    systems.add({s.stage.name, {previous}, {}, [this, run = s.stage.run, always = s.always](World&, const FrameContext&) {
                   if (advancing_ || always) run(time_s_);
                 }});
    previous = s.stage.name;
  }
}

void Runtime::run_frame(double t_s) {
  for (const Stage& s : stages_) s.stage.run(t_s);
}

void Runtime::advance(const FrameContext& f) {
  // The runtime's clock starts where the frame loop's does and moves one step per frame it runs.
  if (frames_ == 0 && !started_) {
    next_time_s_ = f.time_s;
    started_ = true;
  }
  advancing_ = !paused_ || step_requested_;
  step_requested_ = false;
  if (!advancing_) return;
  time_s_ = next_time_s_;
  next_time_s_ += f.dt_s;
  ++frames_;
}

Entity Runtime::hand_entity(HandSide side) {
  Entity found;
  world_.view<Hand>().each([&](Entity e, Hand& h) {
    if (h.side == side) found = e;
  });
  return found;
}

const Hand& Runtime::hand(HandSide side) { return world_.get<Hand>(hand_entity(side)); }
const HandBody* Runtime::hand_body(HandSide side) { return world_.find<HandBody>(hand_entity(side)); }

void Runtime::render() {
  std::vector<HandDrawInput> hands;
  world_.view<Hand>().each([&](Entity e, Hand& hand) {
    if (!hand.shown || !hand.tracked.seen) return;
    const HandBody* body = world_.find<HandBody>(e);
    const auto& joints = body && body->active ? body->joints_world : hand.tracked.joints_world;
    HandDrawInput h;
    for (std::size_t j = 0; j < kHandJointCount; ++j) {
      h.joint_world[j] = to_glm(joints[j]);
      h.radius_m[j] = static_cast<float>(hand.tracked.radius_m[j]);
    }
    if (body && body->holding) h.color = {0.55f, 0.85f, 0.55f, 1.0f};
    hands.push_back(h);
  });
  debug_.clear();
  fill_debug(debug_);
  const bool any_debug = !debug_.lines().empty() || !debug_.points().empty();
  FrameInput frame = scene_renderer_->build(world_, views_, hands, any_debug ? &debug_ : nullptr);
  if (overlay_ && renderer_->begin_overlay()) overlay_();
  renderer_->render(frame);
}

void Runtime::fill_debug(DebugDraw& debug) {
  const DebugViews& v = settings_.debug;
  world_.view<TrackedMarkers, TrackingCameras>().each([&](Entity, TrackedMarkers& markers, TrackingCameras& rig) {
    const auto& points = markers.points;
    if (v.markers) {
      for (const Eigen::Vector3d& p : points) debug.point(to_glm(p), 0.004f, {1.0f, 1.0f, 0.3f, 1.0f});
    }
    if (v.rays) {
      const auto& cameras = markers.point_cameras;
      for (std::size_t i = 0; i < points.size() && i < cameras.size(); ++i) {
        for (const int c : cameras[i]) {
          if (c < 0 || static_cast<std::size_t>(c) >= rig.cameras.size()) continue;
          debug.line(to_glm(rig.cameras[static_cast<std::size_t>(c)].centre_world()), to_glm(points[i]), {1.0f, 0.85f, 0.3f, 0.6f});
        }
      }
    }
    if (v.frusta) {
      for (const Camera& cam : rig.cameras) {
        const CameraIntrinsics& k = cam.intrinsics;
        debug.camera_frustum(to_glm(cam.cam_from_world.inverse()), k.width_px, k.height_px, static_cast<float>(k.fx),
                             static_cast<float>(k.fy), static_cast<float>(k.cx), static_cast<float>(k.cy), 0.25f, {0.3f, 0.9f, 1.0f, 1.0f});
      }
    }
  });
  if (!v.colliders) return;
  for (const HandSide side : {HandSide::kLeft, HandSide::kRight}) {
    const Entity e = hand_entity(side);
    if (const HandBody* body = world_.find<HandBody>(e)) {
      for (const HandCapsule& c : body->capsules) {
        debug.capsule(to_glm(c.a_world), to_glm(c.b_world), static_cast<float>(c.radius_m),
                      c.soft ? glm::vec4(1.0f, 0.5f, 0.1f, 1.0f) : glm::vec4(0.2f, 0.9f, 0.9f, 1.0f));
      }
    }
    // The tracked skeleton, where the physics is aiming the bones.
    const HandInput& in = world_.get<Hand>(e).tracked;
    if (!in.seen) continue;
    for (const HandBone& b : hand_bones()) {
      debug.line(to_glm(in.joints_world[static_cast<std::size_t>(b.from)]), to_glm(in.joints_world[static_cast<std::size_t>(b.to)]),
                 {1.0f, 0.2f, 0.8f, 1.0f});
    }
  }
}

}  // namespace rhot
