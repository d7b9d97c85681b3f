#include "engine/pipeline/Pipeline.h"

#include <numbers>

#include <Eigen/Geometry>
#include <glm/gtc/quaternion.hpp>

#include <cmath>

#include <spdlog/spdlog.h>

#include "engine/core/Transform.h"
#include "engine/core/World.h"
#include "engine/scene/SceneLoader.h"
#include "tracking/camera/RigFile.h"
#include "tracking/core/Check.h"
#include "tracking/geometry/Matching.h"
#include "tracking/rigid/StarSet.h"

namespace rhot {

namespace {

// Where an object's star stands: on the side facing away from the user (-Z), 4 mm clear of the
// surface, its tall side pointing out (the hand closes on the object from above and from the
// user's side, so a star on top or in front would be under the palm).
double star_offset(const Mesh* mesh, const glm::vec3& scale) {
  const auto half = mesh ? shape_half_extents(mesh->shape) : std::nullopt;
  return half ? static_cast<double>(half->z * scale.z) + 0.004 : 0.05;
}

void add_bones(std::vector<Occluder>& out, const HandTruth& hand) {
  for (int j = 0; j < kHandJointCount; ++j) {
    const auto parent = joint_parent(static_cast<HandJoint>(j));
    if (!parent) continue;
    out.push_back({hand.world_from_hand * hand.pose.position_m[static_cast<std::size_t>(*parent)],
                   hand.world_from_hand * hand.pose.position_m[static_cast<std::size_t>(j)],
                   0.8 * hand.pose.radius_m[static_cast<std::size_t>(j)]});
  }
}

}  // namespace

std::expected<std::unique_ptr<Pipeline>, std::string> Pipeline::create(World& world, const SceneDesc& scene, PipelineSettings settings) {
  std::unique_ptr<Pipeline> p(new Pipeline(scene));
  p->settings_ = settings;
  const std::filesystem::path rig_file =
      !settings.rig_file.empty() ? settings.rig_file : scene.settings.rig_file.value_or(settings.asset_dir / "rigs" / "seated-4.yaml");
  auto rig = load_rig(rig_file);
  if (!rig) return std::unexpected(rig.error());
  p->rig_ = *rig;
  const bool video = !settings.video_devices.empty();
  if (video && settings.perfect_hands)
    return std::unexpected(std::string("perfect hands need the simulated rig's truth; video sources have none"));
  if (video && !settings.replay.empty()) return std::unexpected(std::string("choose video devices or a replay, not both"));
  const std::filesystem::path set_file = !settings.star_set.empty() ? settings.star_set : settings.asset_dir / "stars" / "seed-case.json";
  auto set = load_star_set(set_file);
  if (!set) return std::unexpected(set.error());

  // The objects' stars: the set's stars that some entity is tracked by.
  StarSet used;
  used.rules = set->rules;
  std::string error;
  world.view<TrackedBy, Transform>().each([&](Entity e, TrackedBy& by, Transform& t) {
    const auto it = std::find_if(set->stars.begin(), set->stars.end(), [&](const MarkerStar& s) { return s.id == by.star_id; });
    if (it == set->stars.end()) {
      const Name* name = world.find<Name>(e);
      error = (name ? name->value : std::string("an entity")) + ": tracked by star " + std::to_string(by.star_id) + ", which " +
              set_file.string() + " does not have";
      return;
    }
    used.stars.push_back(*it);
    p->tracked_.emplace_back(e, by.star_id);
    if (const Name* name = world.find<Name>(e)) p->name_of_star_[by.star_id] = name->value;
    Rigid3d object_from_star;
    object_from_star.translation = Eigen::Vector3d(0.0, 0.0, -star_offset(world.find<Mesh>(e), t.scale));
    object_from_star.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(std::numbers::pi, Eigen::Vector3d::UnitY()));
    p->object_from_star_[by.star_id] = object_from_star;
  });
  if (!error.empty()) return std::unexpected(error);
  p->star_tracker_ = std::make_unique<StarTracker>(StarLibrary(used));

  for (int h = 0; h < 2; ++h) {
    const auto file = settings.asset_dir / "hands" / (h == 0 ? "low-cost-left.json" : "low-cost-right.json");
    auto layout = load_hand_layout(file);
    if (!layout) return std::unexpected(layout.error());
    p->layouts_[static_cast<std::size_t>(h)] = *layout;
    HandTrackerSettings tracker_settings;
    tracker_settings.filter = settings.filter_hands;
    p->hand_trackers_[static_cast<std::size_t>(h)] =
        std::make_unique<HandTracker>(*layout, reference_open_hand(layout->side), tracker_settings);
  }

  SimulatedRigSettings sim;
  sim.sigma_px = settings.sigma_px;
  sim.seed = settings.seed;
  sim.rate_hz = scene.settings.headset.refresh_hz;
  if (video) {
    VideoSourceSettings vs;
    vs.detector = settings.detector;
    vs.rate_hz = sim.rate_hz;
    auto source = VideoSource::open(*rig, settings.video_devices, vs);
    if (!source) return std::unexpected(rig_file.string() + ": " + source.error());
    p->video_ = std::move(*source);
    p->video_logged_.resize(rig->cameras.size());
  } else {
    p->sim_ = std::make_unique<SimulatedRig>(*rig, std::vector<Trajectory>{}, sim);
    Pipeline* self = p.get();
    p->sim_->set_scripted_markers([self](double) {
      std::vector<Eigen::Vector3d> markers;
      for (int h = 0; h < 2; ++h) {
        const HandTruth& hand = self->truth_->hands[static_cast<std::size_t>(h)];
        for (const Eigen::Vector3d& m : layout_markers(self->layouts_[static_cast<std::size_t>(h)], hand.world_from_hand, hand.pose))
          markers.push_back(m);
      }
      for (const StarLibrary::Star& star : self->star_tracker_->library().stars()) {
        const auto at = self->truth_->world_from_object.find(star.id);
        if (at == self->truth_->world_from_object.end()) continue;
        const Rigid3d world_from_star = at->second * self->object_from_star_.at(star.id);
        for (const Eigen::Vector3d& m : star.markers_m) markers.push_back(world_from_star * m);
      }
      return markers;
    });
  }

  auto physics = HandPhysics::create(world, scene);
  if (!physics) return std::unexpected(physics.error());
  p->physics_ = std::move(*physics);
  if (!settings.replay.empty()) {
    auto recording = load_recording(settings.replay);
    if (!recording) return std::unexpected(recording.error());
    if (!(settings.speed > 0.0) || !std::isfinite(settings.speed)) return std::unexpected("replay speed must be a positive number");
    p->replay_ = std::move(*recording);
  }
  if (!settings.record.empty()) {
    std::vector<std::string> names;
    for (const auto& [id, name] : p->name_of_star_) names.push_back(name);
    auto writer = RecordingWriter::open(settings.record, sim.rate_hz, names);
    if (!writer) return std::unexpected(writer.error());
    p->recorder_ = std::move(*writer);
  }
  return p;
}

void Pipeline::source(double t_s) {
  time_s_ = t_s;
  counts_ = {};
  if (replay_) {
    // The recording's clock runs at the replay speed, which may change between frames.
    replay_clock_s_ = replay_started_ ? replay_clock_s_ + (t_s - replay_last_t_s_) * settings_.speed : t_s * settings_.speed;
    replay_started_ = true;
    replay_last_t_s_ = t_s;
    replayed_ = replay_->at(replay_clock_s_);
    return;
  }
  if (video_) {
    read_video();
  } else {
    truth_ = script_.at(t_s);
    std::vector<Occluder> bones;
    add_bones(bones, truth_->hands[0]);
    add_bones(bones, truth_->hands[1]);
    sim_->set_occluders(std::move(bones));
    frame_ = sim_->next();
  }
  for (const auto& camera : frame_.cameras) counts_.detections += camera.detections.size();
}

void Pipeline::set_speed(double speed) {
  RHOT_PRECONDITION(std::isfinite(speed) && speed > 0.0, "Pipeline::set_speed: speed must be finite and positive");
  settings_.speed = speed;
}

void Pipeline::read_video() {
  if (auto frame = video_->next()) {
    frame_ = std::move(*frame);
  } else {
    if (!source_ended_) spdlog::info("video: the stream has ended after {} frames", frame_.cameras.empty() ? 0 : frame_.index + 1);
    source_ended_ = true;
    frame_.cameras.assign(rig_.cameras.size(), CameraFrame{});
    for (std::size_t c = 0; c < frame_.cameras.size(); ++c) frame_.cameras[c].camera = static_cast<int>(c);
  }
  // A camera's failed reads and bad images are logged at the 1st, 10th, 100th ... of each kind.
  const auto milestone = [](std::uint64_t before, std::uint64_t now) {
    for (std::uint64_t m = 1; m <= now; m *= 10) {
      if (m > before) return true;
    }
    return false;
  };
  for (std::size_t c = 0; c < video_logged_.size(); ++c) {
    const VideoCameraStats& now = video_->stats()[c];
    VideoCameraStats& logged = video_logged_[c];
    if (milestone(logged.bad_images, now.bad_images) || milestone(logged.failed_reads, now.failed_reads)) {
      spdlog::warn("video: camera {} ({}): {} bad image(s), {} failed read(s) so far; last: {}", c, rig_.cameras[c].name, now.bad_images,
                   now.failed_reads, now.last_problem);
      logged = now;
    }
  }
}

void Pipeline::matching() {
  points_.clear();
  point_cameras_.clear();
  if (replay_) return;
  double sum_rms = 0.0;
  for (const MatchedPoint& m : match_and_triangulate(rig_, frame_)) {
    points_.push_back(m.point.position_world);
    point_cameras_.push_back(m.point.cameras);
    sum_rms += m.point.reprojection_rms_px;
  }
  counts_.points = points_.size();
  counts_.mean_reprojection_rms_px = points_.empty() ? 0.0 : sum_rms / static_cast<double>(points_.size());
}

void Pipeline::stars(World& world) {
  if (replay_) {
    for (const auto& [entity, id] : tracked_) {
      const auto name = name_of_star_.find(id);
      if (name == name_of_star_.end() || !world.alive(entity)) continue;
      const auto pose = replayed_.objects.find(name->second);
      if (pose == replayed_.objects.end()) continue;
      Transform& t = world.get<Transform>(entity);
      t.position = glm::vec3(pose->second.translation.cast<float>().x(), pose->second.translation.cast<float>().y(),
                             pose->second.translation.cast<float>().z());
      const Eigen::Quaterniond& q = pose->second.rotation;
      t.rotation = glm::normalize(
          glm::quat(static_cast<float>(q.w()), static_cast<float>(q.x()), static_cast<float>(q.y()), static_cast<float>(q.z())));
      ++counts_.stars_seen;
      counts_.seen_star_ids.push_back(id);
    }
    return;
  }
  const auto& stars = star_tracker_->update(time_s_, points_);
  for (const auto& [entity, id] : tracked_) {
    for (const TrackedStar& s : stars) {
      if (s.id != id || !s.seen_now() || !world.alive(entity)) continue;
      ++counts_.stars_seen;
      counts_.seen_star_ids.push_back(id);
      const Rigid3d world_from_object = s.world_from_star * object_from_star_.at(id).inverse();
      if (!world_from_object.translation.allFinite() || !world_from_object.rotation.coeffs().allFinite()) continue;
      if (const auto name = name_of_star_.find(id); name != name_of_star_.end()) object_poses_[name->second] = world_from_object;
      Transform& t = world.get<Transform>(entity);
      t.position = glm::vec3(world_from_object.translation.cast<float>().x(), world_from_object.translation.cast<float>().y(),
                             world_from_object.translation.cast<float>().z());
      const Eigen::Quaterniond& q = world_from_object.rotation;
      t.rotation = glm::normalize(
          glm::quat(static_cast<float>(q.w()), static_cast<float>(q.x()), static_cast<float>(q.y()), static_cast<float>(q.z())));
    }
  }
}

void Pipeline::hands() {
  if (replay_) {
    inputs_ = replayed_.hands;
    counts_.hands_seen = {inputs_[0].seen, inputs_[1].seen};
    return;
  }
  for (std::size_t h = 0; h < 2; ++h) {
    const TrackedHand& tracked = hand_trackers_[h]->update(time_s_, points_);
    inputs_[h] =
        settings_.perfect_hands && truth_ ? hand_input(truth_->hands[h].world_from_hand, truth_->hands[h].pose) : hand_input(tracked);
    counts_.hands_seen[h] = tracked.hand_seen;
  }
  if (recorder_) {
    RecordedFrame f;
    f.t_s = time_s_;
    f.hands = inputs_;
    f.objects = object_poses_;
    if (auto written = recorder_->write(f); !written) {
      spdlog::error("recording stopped: {}", written.error());
      recorder_.reset();
    }
  }
}

void Pipeline::physics(World& world) {
  physics_->step(world, inputs_);
  if (replay_ || video_ || script_.right_target().empty()) return;  // only the simulated user looks
  const Entity cube = find_named(world, script_.right_target());
  if (const Transform* t = world.find<Transform>(cube))
    script_.reaim(time_s_, Eigen::Vector3d(t->position.x, t->position.y, t->position.z));
}

}  // namespace rhot
