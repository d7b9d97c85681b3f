#include "engine/sim/Demo.h"

#include <cmath>

#include "engine/core/Transform.h"
#include "engine/core/World.h"
#include "engine/math/EigenGlm.h"
#include "engine/scene/SceneLoader.h"
#include "engine/tracked/ReplaySource.h"
#include "tracking/camera/RigFile.h"
#include "tracking/sim/Realism.h"
#include "tracking/sim/SimulatedRig.h"
#include "tracking/net/NodeSource.h"
#include "tracking/rigid/StarSet.h"
#include "tracking/source/VideoSource.h"

namespace rhot {

std::expected<void, std::string> DemoSettings::check() const {
  if (!std::isfinite(sigma_px) || sigma_px < 0.0 || sigma_px > 50.0) {
    return std::unexpected("sigma: the simulated pixel noise must be a number from 0 to 50 pixels, got " + std::to_string(sigma_px));
  }
  if (!std::isfinite(speed) || !(speed > 0.0)) return std::unexpected(std::string("speed: the replay speed must be a positive number"));
  if (auto detector_ok = rhot::check(detector); !detector_ok) return std::unexpected("detector: " + detector_ok.error());
  if (auto world_ok = world.check(); !world_ok) return std::unexpected("world: " + world_ok.error());
  if (auto cameras_ok = colour_cameras.check(); !cameras_ok) return std::unexpected("colour cameras: " + cameras_ok.error());
  if (colour_markers && !node_endpoints.empty()) {
    return std::unexpected(std::string("colour markers through camera nodes: the node protocol (version 1) carries no colour"));
  }
  if (!video_devices.empty() && perfect_hands) {
    return std::unexpected(std::string("perfect hands need the simulated rig's truth; video sources have none"));
  }
  if (!video_devices.empty() && !replay.empty()) return std::unexpected(std::string("choose video devices or a replay, not both"));
  if (!node_endpoints.empty() && (!video_devices.empty() || !replay.empty()))
    return std::unexpected(std::string("choose camera nodes, video devices or a replay, one of them"));
  if (!node_endpoints.empty() && perfect_hands)
    return std::unexpected(std::string("perfect hands need the simulated rig's truth; camera nodes send none"));
  for (const std::string& e : node_endpoints)
    if (auto ok = check_endpoint(e); !ok) return std::unexpected("nodes: " + ok.error());
  if (!replay.empty() && perfect_hands) {
    return std::unexpected(std::string("perfect hands need the simulated rig's truth; a replay has none"));
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

std::expected<std::array<HandLayout, 2>, std::string> demo_hand_layouts(const std::filesystem::path& asset_dir, const StarSet& object_stars,
                                                                        bool colour_markers) {
  std::array<HandLayout, 2> layouts;
  const std::string kind = colour_markers ? "colour" : "low-cost";
  for (std::size_t h = 0; h < 2; ++h) {
    auto layout = load_hand_layout(asset_dir / "hands" / (kind + (h == 0 ? "-left.json" : "-right.json")));
    if (!layout) return std::unexpected(layout.error());
    layouts[h] = std::move(*layout);
  }
  // Hands that could be taken for each other, or for an object, from three markers are refused.
  if (const auto clashes = check_hand_stars(layouts, object_stars); !clashes.empty()) {
    return std::unexpected("hand layouts: " + clashes.front() +
                           (clashes.size() > 1 ? " (and " + std::to_string(clashes.size() - 1) + " more)" : ""));
  }
  return layouts;
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
  auto layouts = demo_hand_layouts(asset_dir, objects->stars, colour_markers);
  if (!layouts) return std::unexpected(layouts.error());
  DemoSimulation out;
  out.script = std::make_unique<DemoScript>(scene);
  out.layouts = *layouts;
  out.objects = std::move(*objects);
  out.world = std::make_shared<DemoWorld>(*out.script, out.layouts, out.objects, independent_hands_seed);
  return out;
}

std::expected<std::unique_ptr<Demo>, std::string> Demo::create(const SceneDesc& scene, Renderer* renderer, DemoSettings settings) {
  if (auto checked = settings.check(); !checked) return std::unexpected(checked.error());
  std::unique_ptr<Demo> d(new Demo());
  d->script_ = std::make_unique<DemoScript>(scene);
  Demo* self = d.get();
  const bool replay = !settings.replay.empty();
  const bool video = !settings.video_devices.empty();
  const auto make_tracking = [&](World&, const TrackedObjects& objects) -> std::expected<std::unique_ptr<ResultSource>, std::string> {
    if (replay) {
      auto source = ReplaySource::open(settings.replay, settings.speed, objects);
      if (!source) return std::unexpected(source.error());
      return std::unique_ptr<ResultSource>(std::move(*source));
    }
    const std::filesystem::path rig_file = !settings.rig_file.empty() ? settings.rig_file
                                           : settings.colour_markers
                                               ? settings.asset_dir / "rigs" / "stereo-640.yaml"
                                               : scene.settings.rig_file.value_or(settings.asset_dir / "rigs" / "seated-4.yaml");
    auto rig = load_rig(rig_file);
    if (!rig) return std::unexpected(rig.error());
    auto loaded_layouts = demo_hand_layouts(settings.asset_dir, objects.stars, settings.colour_markers);
    if (!loaded_layouts) return std::unexpected(loaded_layouts.error());
    const std::array<HandLayout, 2>& layouts = *loaded_layouts;
    const double rate_hz = scene.settings.headset.refresh_hz;
    ColourModel colour_model = default_colour_model();
    if (settings.colour_markers && !settings.colours.empty()) {
      auto loaded = load_colour_model(settings.colours);
      if (!loaded) return std::unexpected(loaded.error().to_string());
      colour_model = std::move(*loaded);
    }
    std::unique_ptr<FrameSource> source;
    if (!settings.node_endpoints.empty()) {
      auto opened = NodeSource::open(*rig, settings.node_endpoints);
      if (!opened) return std::unexpected(opened.error());
      source = std::move(*opened);
    } else if (video) {
      VideoSourceSettings vs;
      vs.detector = settings.detector;
      if (settings.colour_markers) vs.colours = colour_model;
      vs.rate_hz = rate_hz;
      auto opened = VideoSource::open(*rig, settings.video_devices, vs);
      if (!opened) return std::unexpected(rig_file.string() + ": " + opened.error());
      source = std::make_unique<VideoSource>(std::move(*opened));
    } else if (settings.colour_markers) {
      self->world_ = std::make_shared<DemoWorld>(*self->script_, layouts, objects, settings.world.independent_hands ? settings.seed : 0u);
      ColourCameraSettings cs = settings.colour_cameras;
      cs.seed = settings.seed;
      auto cameras = ColourCameras::create(*rig, scene, cs);
      if (!cameras) return std::unexpected(cameras.error());
      std::shared_ptr<DemoWorld> world = self->world_;
      source = std::make_unique<ColourCameraSource>(
          std::move(*cameras), [world](double t) { return world->colour_shot(world->at(t)); }, colour_model);
    } else {
      SimulatedRigSettings sim = settings.world.rig_settings(settings.seed, rate_hz);
      sim.sigma_px = settings.sigma_px;
      auto rig_source = std::make_unique<SimulatedRig>(*rig, std::vector<Trajectory>{}, sim);
      self->world_ = std::make_shared<DemoWorld>(*self->script_, layouts, objects, settings.world.independent_hands ? settings.seed : 0u);
      rig_source->set_world(self->world_);
      source = std::move(rig_source);
    }
    LiveTrackingSettings live_settings;
    live_settings.filter_hands = settings.filter_hands;
    // With a calibration error the tracker believes a rig a little off the one that took the frames.
    if (!video && settings.node_endpoints.empty() && settings.world.calib_error_px > 0.0)
      live_settings.tracker_rig = perturbed_rig(*rig, settings.world.calib_error_px, settings.seed);
    auto live = std::make_unique<LiveTracking>(std::move(source), objects, layouts, live_settings);
    self->live_ = live.get();
    return std::unique_ptr<ResultSource>(std::move(live));
  };
  RuntimeSettings rs;
  rs.star_set = !settings.star_set.empty() ? settings.star_set : settings.asset_dir / "stars" / "seed-case.json";
  rs.record = settings.record;
  rs.stream = settings.stream;
  rs.debug = settings.debug;
  rs.predict = settings.predict;
  rs.latency_window_frames = settings.latency_window_frames;
  auto runtime = Runtime::create(scene, renderer, rs, make_tracking);
  if (!runtime) return std::unexpected(runtime.error());
  d->runtime_ = std::move(*runtime);

  if (d->world_) {
    Runtime& r = *d->runtime_;
    if (settings.perfect_hands) {
      // The script's hands at the frame's own time (the simulated world may have been asked for
      // later moments since, by unsynchronised cameras).
      r.add_stage("hands", {"perfect-hands", [self](double t_s) {
                              const SceneTruth truth = self->script_->at(t_s);
                              TrackingResults& results = self->runtime_->tracking().results();
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
    if (!d->script_->right_target().empty()) {
      r.add_stage("physics", {"look", [self](double t_s) {
                                World& world = self->runtime_->world();
                                const Entity cube = find_named(world, self->script_->right_target());
                                if (const Transform* t = world.find<Transform>(cube)) {
                                  self->script_->reaim(t_s, to_eigen(t->position));
                                }
                              }});
    }
  }
  return d;
}

}  // namespace rhot
