#include "engine/sim/Demo.h"

#include <cmath>

#include "engine/core/Transform.h"
#include "engine/core/World.h"
#include "engine/math/EigenGlm.h"
#include "engine/scene/Components.h"
#include "engine/scene/SceneLoader.h"
#include "tracking/camera/RigFile.h"
#include "tracking/sim/Realism.h"
#include "tracking/sim/SimulatedRig.h"
#include "tracking/rigid/StarSet.h"

namespace rhot {

std::expected<void, std::string> DemoSettings::check() const {
  if (!std::isfinite(sigma_px) || sigma_px < 0.0 || sigma_px > 50.0) {
    return std::unexpected("sigma: the simulated pixel noise must be a number from 0 to 50 pixels, got " + std::to_string(sigma_px));
  }
  if (auto launch_ok = LaunchSettings::check(); !launch_ok) return launch_ok;
  if (auto world_ok = world.check(); !world_ok) return std::unexpected("world: " + world_ok.error());
  if (auto cameras_ok = colour_cameras.check(); !cameras_ok) return std::unexpected("colour cameras: " + cameras_ok.error());
  if (perfect_hands) {
    if (!video_devices.empty())
      return std::unexpected(std::string("perfect hands need the simulated rig's truth; video sources have none"));
    if (!node_endpoints.empty())
      return std::unexpected(std::string("perfect hands need the simulated rig's truth; camera nodes send none"));
    if (!replay.empty()) return std::unexpected(std::string("perfect hands need the simulated rig's truth; a replay has none"));
  }
  return {};
}

DemoWorld::DemoWorld(const DemoScript& script, const std::array<HandLayout, 2>& layouts, const TrackedObjects& objects,
                     unsigned independent_hands_seed)
    : script_(script), layouts_(layouts), hands_seed_(independent_hands_seed) {
  // The stars in the tracker's library order, as the markers have always been numbered.
  const StarLibrary library(objects.stars);
  for (const StarLibrary::Star& star : library.stars()) {
    const TrackedObject* object = objects.by_star(star.id);
    if (object) stars_.push_back({star.id, object->object_from_star, star.markers_m});
  }
}

SceneTruth DemoWorld::truth_at(double t_s) const {
  SceneTruth truth = script_.at(t_s);
  if (hands_seed_ != 0) {
    // Users' own hands: each bone of the script's pose scaled (the left hand a different user's
    // hand than the right: its own seed).
    for (std::size_t h = 0; h < 2; ++h) truth.hands[h].pose = independent_hand(truth.hands[h].pose, hands_seed_ + static_cast<unsigned>(h));
  }
  return truth;
}

WorldSnapshot DemoWorld::at(double t_s) {
  truth_ = truth_at(t_s);
  WorldSnapshot out;
  for (const HandTruth& hand : truth_->hands) {
    for (const Occluder& o : hand_bone_occluders(hand.world_from_hand, hand.pose)) out.occluders.push_back(o);
  }
  for (std::size_t h = 0; h < 2; ++h) {
    const HandTruth& hand = truth_->hands[h];
    for (const Eigen::Vector3d& m : layout_markers(layouts_[h], hand.world_from_hand, hand.pose)) out.markers_m.push_back(m);
  }
  for (const Star& star : stars_) {
    const auto at = truth_->world_from_object.find(star.id);
    if (at == truth_->world_from_object.end()) continue;
    const Rigid3d world_from_star = at->second * star.object_from_star;
    for (const Eigen::Vector3d& m : star.markers_m) out.markers_m.push_back(world_from_star * m);
  }
  for (const Occluder& o : body_occluders()) out.occluders.push_back(o);
  return out;
}

std::vector<Occluder> DemoWorld::body_occluders() const {
  std::vector<Occluder> out;
  if (bodies_ == nullptr || !truth_) return out;
  bodies_->view<Mesh, PhysicsBody, WorldTransform>().each([&](Entity e, const Mesh& mesh, const PhysicsBody&, const WorldTransform& wt) {
    if (bodies_->has<Disabled>(e)) return;
    const glm::mat4& m = wt.world_from_local;
    // The pose without the scale (each axis's length is its scale), and the scale kept apart.
    const Eigen::Vector3d scale(static_cast<double>(glm::length(glm::vec3(m[0]))), static_cast<double>(glm::length(glm::vec3(m[1]))),
                                static_cast<double>(glm::length(glm::vec3(m[2]))));
    if (!(scale.minCoeff() > 1e-9) || !scale.allFinite()) return;
    Eigen::Matrix3d rotation;
    for (int c = 0; c < 3; ++c) rotation.col(c) = to_eigen(glm::vec3(m[c])) / scale(c);
    Rigid3d pose{Eigen::Quaterniond(rotation).normalized(), to_eigen(glm::vec3(m[3]))};
    if (const TrackedBy* tracked = bodies_->find<TrackedBy>(e)) {
      // A star-tracked object's world pose is the tracker's: the cameras see the true one.
      const auto at = truth_->world_from_object.find(tracked->star_id);
      if (at != truth_->world_from_object.end()) pose = at->second;
    }
    if (!pose.translation.allFinite() || !pose.rotation.coeffs().allFinite()) return;
    if (const auto* box = std::get_if<BoxShape>(&mesh.shape)) {
      out.push_back(Occluder::box(pose.translation, pose.rotation, 0.5 * to_eigen(box->size_m).cwiseProduct(scale)));
    } else if (const auto* sphere = std::get_if<SphereShape>(&mesh.shape)) {
      out.push_back({pose.translation, pose.translation, static_cast<double>(sphere->radius_m) * scale.maxCoeff()});
    } else if (const auto* capsule = std::get_if<CapsuleShape>(&mesh.shape)) {
      const double radius = static_cast<double>(capsule->radius_m);
      const double half = std::max(0.0, 0.5 * static_cast<double>(capsule->height_m) - radius) * scale.y();
      const Eigen::Vector3d axis = pose.rotation * Eigen::Vector3d::UnitY();
      out.push_back({pose.translation - half * axis, pose.translation + half * axis, radius * std::max(scale.x(), scale.z())});
    }
  });
  return out;
}

ColourShot DemoWorld::colour_shot(const WorldSnapshot& snapshot) const {
  ColourShot shot;
  if (!truth_) return shot;
  for (const HandTruth& hand : truth_->hands) shot.hands.push_back({hand.world_from_hand, hand.pose});
  std::size_t m = 0;
  for (const HandLayout& layout : layouts_) {
    const std::vector<int> colours = layout_marker_colours(layout);
    for (std::size_t i = 0; i < colours.size() && m < snapshot.markers_m.size(); ++i, ++m) {
      shot.markers.push_back({snapshot.markers_m[m], 0.0005 * layout.marker_diameter_mm, colours[i] >= 0 ? colours[i] : kStarColour});
    }
  }
  for (; m < snapshot.markers_m.size(); ++m) shot.markers.push_back({snapshot.markers_m[m], 0.007, kStarColour});
  return shot;
}

std::expected<DemoSimulation, std::string> make_demo_simulation(const SceneDesc& scene, const std::filesystem::path& asset_dir,
                                                                const std::filesystem::path& star_set, unsigned independent_hands_seed,
                                                                bool colour_markers) {
  const std::filesystem::path set_file = star_set.empty() ? asset_dir / "stars" / "seed-case.json" : star_set;
  auto set = load_star_set(set_file);
  if (!set) return std::unexpected(set.error());
  World world;
  instantiate(scene, world);
  auto objects = find_tracked_objects(world, *set, set_file);
  if (!objects) return std::unexpected(objects.error());
  auto layouts = default_hand_layouts(asset_dir, objects->stars, colour_markers);
  if (!layouts) return std::unexpected(layouts.error());
  DemoSimulation out;
  out.script = std::make_unique<DemoScript>(scene);
  out.layouts = *layouts;
  out.objects = std::move(*objects);
  out.world = std::make_shared<DemoWorld>(*out.script, out.layouts, out.objects, independent_hands_seed);
  return out;
}

namespace {

// The demo's simulated source: the simulated rig photographing the demo's world, or, with colour
// markers, colour cameras drawn by the renderer.
std::expected<CustomSource, std::string> simulated_source(const SourceRequest& request, const SceneDesc& scene,
                                                          const DemoSettings& settings, const DemoScript& script,
                                                          std::shared_ptr<DemoWorld>& world) {
  world = std::make_shared<DemoWorld>(script, request.layouts, request.objects, settings.world.independent_hands ? settings.seed : 0u);
  CustomSource out;
  if (settings.colour_markers) {
    ColourCameraSettings cs = settings.colour_cameras;
    cs.seed = settings.seed;
    auto cameras = ColourCameras::create(request.rig, scene, cs);
    if (!cameras) return std::unexpected(cameras.error());
    std::shared_ptr<DemoWorld> shot_world = world;
    out.source = std::make_unique<ColourCameraSource>(
        std::move(*cameras), [shot_world](double t) { return shot_world->colour_shot(shot_world->at(t)); }, request.colours);
  } else {
    SimulatedRigSettings sim = settings.world.rig_settings(settings.seed, request.rate_hz);
    sim.sigma_px = settings.sigma_px;
    auto rig_source = std::make_unique<SimulatedRig>(request.rig, std::vector<Trajectory>{}, sim);
    rig_source->set_world(world);
    out.source = std::move(rig_source);
  }
  // With a calibration error the tracker believes a rig a little off the one that took the frames.
  if (settings.world.calib_error_px > 0.0) out.tracker_rig = perturbed_rig(request.rig, settings.world.calib_error_px, settings.seed);
  return out;
}

}  // namespace

std::expected<std::unique_ptr<Demo>, std::string> Demo::create(const SceneDesc& scene, Renderer* renderer, DemoSettings settings) {
  if (auto checked = settings.check(); !checked) return std::unexpected(checked.error());
  std::unique_ptr<Demo> d(new Demo());
  d->script_ = std::make_unique<DemoScript>(scene);
  Demo* self = d.get();
  const SourceFactory simulated = [&](const SourceRequest& request) {
    return simulated_source(request, scene, settings, *self->script_, self->world_);
  };
  auto launched = Launch::create(scene, renderer, settings, simulated);
  if (!launched) return std::unexpected(launched.error());
  d->launch_ = std::move(*launched);
  if (d->world_ && settings.world.occluding_bodies) d->world_->hide_behind_bodies(d->world());
  d->add_stages(settings);
  return d;
}

void Demo::add_stages(const DemoSettings& settings) {
  Demo* self = this;
  if (world_) {
    Runtime& r = runtime();
    if (settings.perfect_hands) {
      // The script's hands at the frame's own time (the simulated world may have been asked for
      // later moments since, by unsynchronised cameras).
      r.add_stage("hands", {"perfect-hands", [self](double t_s) {
                              const SceneTruth truth = self->script_->at(t_s);
                              TrackingResults& results = self->runtime().tracking().results();
                              for (std::size_t h = 0; h < 2; ++h) {
                                results.hands[h] = hand_input(truth.hands[h].world_from_hand, truth.hands[h].pose);
                              }
                            }});
    }
    // The drawn hands against the truth at capture and at display time. The simulation's clock
    // is the runtime's: the display time on it is the capture time plus the measured latency.
    r.add_displayed_observer([self](const DisplayedFrame& f) {
      const double latency_s = f.moments.display_s - f.moments.capture_s;
      const SceneTruth at_capture = self->world_->truth_at(f.t_s);
      const SceneTruth at_display = self->world_->truth_at(f.t_s + latency_s);
      PredictionErrors& e = self->prediction_errors_;
      for (std::size_t h = 0; h < 2; ++h) {
        if (!f.seen[h]) continue;
        const HandInput then = hand_input(at_capture.hands[h].world_from_hand, at_capture.hands[h].pose);
        const HandInput shown = hand_input(at_display.hands[h].world_from_hand, at_display.hands[h].pose);
        for (std::size_t j = 0; j < kHandJointCount; ++j) {
          ++e.joints;
          e.at_capture_sum_m += (f.tracked[h][j] - then.joints_world[j]).norm();
          e.predicted_at_display_sum_m += (f.predicted[h][j] - shown.joints_world[j]).norm();
          e.tracked_at_display_sum_m += (f.tracked[h][j] - shown.joints_world[j]).norm();
          e.horizon_sum_s += f.horizon_s;
        }
      }
      for (const auto& [id, poses] : f.objects) {
        const auto then = at_capture.world_from_object.find(id);
        const auto shown = at_display.world_from_object.find(id);
        if (then == at_capture.world_from_object.end() || shown == at_display.world_from_object.end()) continue;
        ++e.objects;
        e.object_at_capture_sum_m += (poses.first.translation - then->second.translation).norm();
        e.object_predicted_at_display_sum_m += (poses.second.translation - shown->second.translation).norm();
        e.object_tracked_at_display_sum_m += (poses.first.translation - shown->second.translation).norm();
      }
    });
    if (!script_->right_target().empty()) {
      r.add_stage("physics", {"look", [self](double t_s) {
                                World& world = self->runtime().world();
                                const Entity cube = find_named(world, self->script_->right_target());
                                if (const Transform* t = world.find<Transform>(cube)) {
                                  self->script_->reaim(t_s, to_eigen(t->position));
                                }
                              }});
    }
  }
}

}  // namespace rhot
