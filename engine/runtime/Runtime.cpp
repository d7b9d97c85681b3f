#include "engine/runtime/Runtime.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <thread>

#include <spdlog/spdlog.h>

#include "base/Check.h"
#include "base/SteadyClock.h"
#include "engine/core/Transform.h"
#include "engine/math/EigenGlm.h"
#include "engine/render/StereoCamera.h"
#include "engine/render/XrHeadset.h"
#include "engine/scene/SceneLoader.h"
#include "tracking/hand/JointFrames.h"
#include "tracking/rigid/StarSet.h"

namespace rhot {

std::expected<std::unique_ptr<Runtime>, std::string> Runtime::create(const SceneDesc& scene, Renderer* renderer,
                                                                     const RuntimeSettings& settings,
                                                                     const TrackingFactory& make_tracking) {
  std::unique_ptr<Runtime> r(new Runtime());
  r->scene_ = scene;
  r->settings_ = settings;
  r->latency_ = LatencyStats(settings.latency_window_frames);
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
  if (!settings.stream.empty()) {
    const auto target = parse_stream_url(settings.stream);
    if (!target) return std::unexpected(target.error());
    auto stream = OscStream::open(*target);
    if (!stream) return std::unexpected(stream.error());
    r->stream_ = std::move(*stream);
    for (const TrackedObject& o : r->objects_.objects) {
      if (!o.name.empty()) r->stream_names_[o.star_id] = o.name;
    }
  }

  Runtime* self = r.get();
  for (TrackingStage& s : r->tracking_->stages()) r->stages_.push_back({std::move(s), false});
  r->stages_.push_back({{"tracked", [self](double) {
                           self->pose_s_ = steady_now_s();
                           const TrackingResults& results = self->tracking_->results();
                           apply_tracking_results(self->world_, results, self->objects_);
                           // Velocities against the capture times where the source knows them
                           // (real cameras' frames come unevenly), else the runtime's clock (the
                           // simulation's own: its world moves on it).
                           const double t = std::isfinite(results.capture_steady_s) ? results.capture_steady_s : results.t_s;
                           for (std::size_t h = 0; h < 2; ++h) {
                             self->hand_motion_[h].update(t, results.hands[h].joints_world, results.hands[h].seen);
                           }
                           for (const TrackedObject& o : self->objects_.objects) {
                             const auto pose = results.world_from_object.find(o.star_id);
                             const bool seen = pose != results.world_from_object.end();
                             self->object_motion_[o.star_id].update(t, seen ? pose->second : Rigid3d{}, seen);
                           }
                         }}});
  r->hand_motion_.assign(2, MotionPredictor(kHandJointCount));
  // The stage is there whether or not the block can be had now (another rhot may be publishing):
  // publish() takes it over once it can.
  if (settings.publish_hands) r->stages_.push_back({{"publish", [self](double) { self->publish(); }}});
  if (r->stream_) {
    r->stages_.push_back({{"stream", [self](double) { self->stream_->send(self->tracking_->results(), self->stream_names_); }}});
  }
  r->stages_.push_back({{"transforms", [self](double) { update_world_transforms(self->world_); }}, true});
  r->stages_.push_back({{"physics", [self](double) {
                           self->physics_->step(self->world_);
                           update_world_transforms(self->world_);  // dynamic bodies moved; children follow
                         }}});
  // After the physics: the recording has what the hands held and why they grasped or let go.
  if (r->recorder_) r->stages_.push_back({{"record", [self](double) { self->record(); }}});
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

void Runtime::wait_for_headset() {
  XrHeadset* xr = renderer_ != nullptr ? renderer_->headset() : nullptr;
  if (xr == nullptr) return;
  headset_waited_ = true;
  xr->poll_events();
  // No frame to wait for (the session not running, or the runtime failing): idle rather than spin.
  const bool waited = xr->session_running() && xr->begin_frame().has_value();
  if (!waited && !xr->should_exit()) std::this_thread::sleep_for(std::chrono::milliseconds(5));
}

void Runtime::advance(const FrameContext& f) {
  XrHeadset* xr = renderer_ != nullptr ? renderer_->headset() : nullptr;
  if (xr != nullptr && !headset_waited_) wait_for_headset();
  headset_waited_ = false;
  frame_start_s_ = steady_now_s();
  pose_s_ = frame_start_s_;
  // The headset's refresh, anchored at the first frame's start.
  if (!vsync_) vsync_.emplace(1.0 / scene_.settings.headset.refresh_hz, frame_start_s_);
  // The runtime's clock starts where the frame loop's does and moves one step per frame it runs.
  if (frames_ == 0 && !started_) {
    next_time_s_ = f.time_s;
    started_ = true;
  }
  // Without the headset's focus (another application has it, or the session is not running) the
  // simulation pauses; the frames are still drawn.
  advancing_ = (!paused_ || step_requested_) && (xr == nullptr || xr->focused());
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

void Runtime::record() {
  const auto name_of = [&](Entity e) {
    const Name* name = world_.alive(e) ? world_.find<Name>(e) : nullptr;
    return name ? name->value : std::string("entity ") + std::to_string(e.index);
  };
  std::array<std::string, 2> holding;
  for (const HandSide side : {HandSide::kLeft, HandSide::kRight}) {
    if (const auto held = physics_->grasp().holding(side)) holding[side == HandSide::kLeft ? 0 : 1] = name_of(*held);
  }
  std::vector<RecordedGraspEvent> events;
  for (const InteractionEvent& e : physics_->events()) {
    if ((e.type != InteractionEventType::kGrasp && e.type != InteractionEventType::kRelease) || !e.hand) continue;
    events.push_back({event_name(e.type), *e.hand == HandSide::kLeft ? "left" : "right", name_of(e.object), e.reason});
  }
  recorder_->record(tracking_->results(), holding, events);
}

void Runtime::publish() {
  if (!hand_share_) {
    // At the first frame, then once a second while another process holds the block.
    const double now = steady_now_s();
    if (now - hand_share_tried_s_ < 1.0) return;
    hand_share_tried_s_ = now;
    auto writer = HandShareWriter::open(hand_share_name());
    if (!writer) {
      if (!hand_share_warned_) spdlog::warn("the hands are not published for other processes: {}", writer.error());
      hand_share_warned_ = true;
      return;
    }
    hand_share_ = std::move(*writer);
    if (hand_share_warned_) spdlog::info("the hands are published in {} from now on", hand_share_->name());
  }
  const TrackingResults& results = tracking_->results();
  HandShareSnapshot snap{};
  snap.capture_s = std::isfinite(results.capture_steady_s) ? results.capture_steady_s : frame_start_s_;
  snap.published_s = steady_now_s();
  snap.frame = frames_;
  const Eigen::Matrix4f w = settings_.world_from_stage.matrix().cast<float>();
  std::copy(w.data(), w.data() + 16, snap.world_from_stage);  // Eigen is column-major, as the format
  for (std::size_t h = 0; h < 2; ++h) {
    const HandInput& in = results.hands[h];
    HandShareHand& out = snap.hands[h];
    if (!in.seen || !in.world_from_hand.is_finite()) continue;
    const auto orientations = joint_orientations(in.world_from_hand.rotation, in.joints_world);
    bool finite = true;
    for (std::size_t j = 0; j < kHandJointCount; ++j) {
      HandShareJoint& joint = out.joints[j];
      const Eigen::Vector3d v = hand_motion_[h].velocity(j);
      const Eigen::Quaterniond& q = orientations[j];
      const double values[] = {in.joints_world[j].x(),
                               in.joints_world[j].y(),
                               in.joints_world[j].z(),
                               q.x(),
                               q.y(),
                               q.z(),
                               q.w(),
                               in.radius_m[j],
                               v.x(),
                               v.y(),
                               v.z()};
      float* fields[] = {&joint.position[0],    &joint.position[1],    &joint.position[2],    &joint.orientation[0],
                         &joint.orientation[1], &joint.orientation[2], &joint.orientation[3], &joint.radius,
                         &joint.velocity[0],    &joint.velocity[1],    &joint.velocity[2]};
      for (std::size_t k = 0; k < std::size(values); ++k) {
        finite = finite && std::isfinite(values[k]);
        *fields[k] = static_cast<float>(values[k]);
      }
    }
    out.tracked = finite ? 1u : 0u;  // a hand with anything not finite is not published
  }
  hand_share_->publish(snap);
}

void Runtime::render() {
  collect_displayed();
  XrHeadset* xr = renderer_->headset();
  if (xr != nullptr) {
    // Drawn for the headset's frame, if one has begun, from where its eyes will be when it is shown.
    if (!xr->current_frame()) return;
    const HeadsetSettings& hs = scene_.settings.headset;
    if (auto located = xr->locate_views(hs.near_m, hs.far_m)) views_ = *located;
  }
  // When this frame will be shown: the refresh at or after the GPU's recent time per frame from now.
  const double now = steady_now_s();
  std::vector<double> gpu(recent_gpu_s_.begin(), recent_gpu_s_.end());
  std::sort(gpu.begin(), gpu.end());
  const double gpu_s = gpu.empty() ? 0.0 : gpu[gpu.size() / 2];
  PendingFrame pending;
  DisplayedFrame& shown = pending.shown;
  const TrackingResults& results = tracking_->results();
  shown.t_s = results.t_s;
  shown.moments.capture_s = std::isfinite(results.capture_steady_s) ? std::min(results.capture_steady_s, pose_s_) : frame_start_s_;
  shown.moments.pose_s = pose_s_;
  // The headset's runtime says when the frame will be shown; else the refresh after the GPU's work.
  shown.predicted_display_s = xr != nullptr ? xr->current_frame()->display_s : vsync_ ? vsync_->next_at_or_after(now + gpu_s) : now;
  // Paused, the poses are old and stay put: nothing to predict.
  shown.horizon_s =
      settings_.predict && advancing_ ? std::clamp(shown.predicted_display_s - shown.moments.capture_s, 0.0, kMaxPredictionHorizon_s) : 0.0;
  for (std::size_t h = 0; h < 2; ++h) {
    const HandInput& in = results.hands[h];
    shown.seen[h] = in.seen;
    shown.tracked[h] = in.joints_world;
    const std::vector<Eigen::Vector3d> ahead = hand_motion_[h].predict(in.joints_world, shown.horizon_s);
    std::copy(ahead.begin(), ahead.end(), shown.predicted[h].begin());
  }

  std::vector<HandDrawInput> hands;
  world_.view<Hand>().each([&](Entity e, Hand& hand) {
    if (!hand.shown || !hand.tracked.seen) return;
    const HandBody* body = world_.find<HandBody>(e);
    const auto& joints = body && body->active ? body->joints_world : hand.tracked.joints_world;
    // Moved on as the tracked hand moves, to where it will be when the frame is shown.
    const auto side = static_cast<std::size_t>(hand.side == HandSide::kLeft ? 0 : 1);
    const std::vector<Eigen::Vector3d> drawn = hand_motion_[side].predict(joints, shown.horizon_s);
    HandDrawInput h;
    for (std::size_t j = 0; j < kHandJointCount; ++j) {
      h.joint_world[j] = to_glm(drawn[j]);
      h.radius_m[j] = static_cast<float>(hand.tracked.radius_m[j]);
    }
    if (body && body->holding) h.color = {0.55f, 0.85f, 0.55f, 1.0f};
    hands.push_back(h);
  });
  // The tracked objects, likewise: drawn moved on to the display time (their WorldTransform for
  // this frame's drawing only; physics and the next frame see the tracked pose).
  std::vector<std::pair<Entity, glm::mat4>> restore;
  for (const TrackedObject& o : objects_.objects) {
    const auto pose = results.world_from_object.find(o.star_id);
    const auto motion = object_motion_.find(o.star_id);
    if (pose == results.world_from_object.end() || motion == object_motion_.end() || !world_.alive(o.entity)) continue;
    const Rigid3d ahead = motion->second.predict(pose->second, shown.horizon_s);
    shown.objects[o.star_id] = {pose->second, ahead};
    WorldTransform* wt = world_.find<WorldTransform>(o.entity);
    const glm::mat4 moved = to_glm(ahead * pose->second.inverse());
    if (wt == nullptr || !std::isfinite(moved[3][0] + moved[3][1] + moved[3][2])) continue;
    restore.emplace_back(o.entity, wt->world_from_local);
    wt->world_from_local = moved * wt->world_from_local;
  }
  debug_.clear();
  fill_debug(debug_);
  const bool any_debug = !debug_.lines().empty() || !debug_.points().empty();
  FrameInput frame = scene_renderer_->build(world_, views_, hands, any_debug ? &debug_ : nullptr);
  for (const auto& [entity, world_from_local] : restore) world_.get<WorldTransform>(entity).world_from_local = world_from_local;
  if (overlay_ && renderer_->begin_overlay()) overlay_();
  renderer_->render(frame);
  shown.moments.submit_s = std::max(steady_now_s(), shown.moments.pose_s);
  pending.renderer_frame = renderer_->frames_submitted() - 1;
  // A frame drawn while paused shows old poses: it has no latency of its own.
  if (advancing_) pending_.push_back(std::move(pending));
  collect_displayed();
}

void Runtime::collect_displayed() {
  // A copy: an observer may read the eyes back, which completes another frame.
  const std::optional<FrameCompletion> done = renderer_->last_completed();
  if (!done) return;
  while (!pending_.empty() && pending_.front().renderer_frame <= done->frame) {
    PendingFrame p = std::move(pending_.front());
    pending_.pop_front();
    if (p.renderer_frame != done->frame) continue;  // finished before a render() of someone else's: its time is lost
    recent_gpu_s_.push_back(std::max(0.0, done->done_s - done->submitted_s));
    if (recent_gpu_s_.size() > 15) recent_gpu_s_.pop_front();
    if (renderer_->info().gpu_timings) {
      for (std::size_t e = 0; e < 2; ++e) {
        gpu_eye_ms_[e].push_back(done->gpu_eye_ms[e]);
        if (gpu_eye_ms_[e].size() > settings_.latency_window_frames) gpu_eye_ms_[e].pop_front();  // the latency's window
      }
    }
    FrameMoments& m = p.shown.moments;
    // Shown at its predicted display time with a headset (or when it was done, if later), else at
    // the refresh after it was done.
    const double shown_s = renderer_->headset() != nullptr ? std::max(p.shown.predicted_display_s, done->done_s)
                           : vsync_                        ? vsync_->next_at_or_after(done->done_s)
                                                           : done->done_s;
    m.display_s = std::max(shown_s, m.submit_s);
    latency_.record(m);
    for (const auto& observer : displayed_observers_) observer(p.shown);
  }
}

std::optional<OscStream::Stats> Runtime::stream_stats() const {
  if (!stream_) return std::nullopt;
  stream_->flush();
  return stream_->stats();
}

std::optional<std::array<TimingSummary, 2>> Runtime::gpu_eye_ms() const {
  if (gpu_eye_ms_[0].empty()) return std::nullopt;
  std::array<TimingSummary, 2> out;
  for (std::size_t e = 0; e < 2; ++e) {
    const std::vector<double> v(gpu_eye_ms_[e].begin(), gpu_eye_ms_[e].end());
    out[e].count = v.size();
    out[e].p50_ms = percentile(v, 0.5);
    out[e].p99_ms = percentile(v, 0.99);
    out[e].max_ms = *std::max_element(v.begin(), v.end());
    double sum = 0.0;
    for (const double x : v) sum += x;
    out[e].mean_ms = sum / static_cast<double>(v.size());
  }
  return out;
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
