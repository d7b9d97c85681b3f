#include "engine/launch/Launch.h"

#include <cmath>
#include <memory>
#include <string>

#include "base/Jobs.h"
#include "engine/tracked/ReplaySource.h"
#include "tracking/camera/RigFile.h"
#include "tracking/net/NodeSource.h"
#include "tracking/source/VideoSource.h"

namespace rhot {

std::expected<void, std::string> LaunchSettings::check() const {
  if (!std::isfinite(speed) || !(speed > 0.0)) return std::unexpected(std::string("speed: the replay speed must be a positive number"));
  if (threads < 0 || threads > kMaxThreads)
    return std::unexpected("threads: " + std::to_string(threads) + " is not a thread count (0: every core, at most " +
                           std::to_string(kMaxThreads) + ")");
  if (auto detector_ok = rhot::check(detector); !detector_ok) return std::unexpected("detector: " + detector_ok.error());
  if (colour_markers && !node_endpoints.empty()) {
    return std::unexpected(std::string("colour markers through camera nodes: the node protocol (version 1) carries no colour"));
  }
  if (!video_devices.empty() && !replay.empty()) return std::unexpected(std::string("choose video devices or a replay, not both"));
  if (!node_endpoints.empty() && (!video_devices.empty() || !replay.empty()))
    return std::unexpected(std::string("choose camera nodes, video devices or a replay, one of them"));
  for (const std::string& e : node_endpoints)
    if (auto ok = parse_node_address(e); !ok) return std::unexpected("nodes: " + ok.error());
  return {};
}

std::filesystem::path LaunchSettings::rig_for(const SceneDesc& scene) const {
  if (!rig_file.empty()) return rig_file;
  if (colour_markers) return asset_dir / "rigs" / "stereo-640.yaml";
  return scene.settings.rig_file.value_or(asset_dir / "rigs" / "seated-4.yaml");
}

std::expected<std::array<HandLayout, 2>, std::string> default_hand_layouts(const std::filesystem::path& asset_dir,
                                                                           const StarSet& object_stars, bool colour_markers) {
  std::array<HandLayout, 2> layouts;
  const std::string kind = colour_markers ? "colour" : "low-cost";
  for (std::size_t h = 0; h < 2; ++h) {
    const std::filesystem::path file = asset_dir / "hands" / (kind + (h == 0 ? "-left.json" : "-right.json"));
    auto layout = load_hand_layout(file);
    if (!layout) return std::unexpected(layout.error());
    if (!layout->has_hand_star()) return std::unexpected(file.string() + ": " + camera_hand_star_problem(*layout));
    layouts[h] = std::move(*layout);
  }
  // Hands that could be taken for each other, or for an object, from three markers are refused.
  if (const auto clashes = check_hand_stars(layouts, object_stars); !clashes.empty()) {
    return std::unexpected("hand layouts: " + clashes.front() +
                           (clashes.size() > 1 ? " (and " + std::to_string(clashes.size() - 1) + " more)" : ""));
  }
  return layouts;
}

namespace {

// The frame source the settings name: camera nodes, video devices, or the application's own.
std::expected<CustomSource, std::string> open_frame_source(const LaunchSettings& settings, const std::filesystem::path& rig_file,
                                                           const SourceRequest& request, const SourceFactory& custom,
                                                           const std::shared_ptr<JobPool>& jobs) {
  CustomSource out;
  if (!settings.node_endpoints.empty()) {
    NodeSourceSettings ns;
    ns.security = settings.node_security;
    auto opened = NodeSource::open(request.rig, settings.node_endpoints, ns);
    if (!opened) return std::unexpected(opened.error());
    out.source = std::move(*opened);
  } else if (!settings.video_devices.empty()) {
    VideoSourceSettings vs;
    vs.detector = settings.detector;
    if (settings.colour_markers) vs.colours = request.colours;
    vs.rate_hz = request.rate_hz;
    vs.jobs = jobs;  // the tracker's one pool (none: one thread)
    vs.threads = 1;
    auto opened = VideoSource::open(request.rig, settings.video_devices, vs);
    if (!opened) return std::unexpected(rig_file.string() + ": " + opened.error());
    out.source = std::make_unique<VideoSource>(std::move(*opened));
  } else if (custom) {
    auto made = custom(request);
    if (!made) return std::unexpected(made.error());
    out = std::move(*made);
    if (!out.source) return std::unexpected(std::string("the application's source factory returned no source"));
  } else {
    return std::unexpected(std::string("no source: name video devices, camera nodes or a recording to replay"));
  }
  return out;
}

}  // namespace

std::expected<std::unique_ptr<Launch>, std::string> Launch::create(const SceneDesc& scene, Renderer* renderer,
                                                                   const LaunchSettings& settings, const SourceFactory& custom) {
  if (auto checked = settings.check(); !checked) return std::unexpected(checked.error());
  std::unique_ptr<Launch> launched(new Launch());
  Launch* self = launched.get();
  const auto make_tracking = [&](World&, const TrackedObjects& objects) -> std::expected<std::unique_ptr<ResultSource>, std::string> {
    if (!settings.replay.empty()) {
      auto source = ReplaySource::open(settings.replay, settings.speed, objects);
      if (!source) return std::unexpected(source.error());
      return std::unique_ptr<ResultSource>(std::move(*source));
    }
    const std::filesystem::path rig_file = settings.rig_for(scene);
    auto rig = load_rig(rig_file);
    if (!rig) return std::unexpected(rig.error());
    auto layouts = default_hand_layouts(settings.asset_dir, objects.stars, settings.colour_markers);
    if (!layouts) return std::unexpected(layouts.error());
    ColourModel colour_model = default_colour_model();
    if (settings.colour_markers && !settings.colours.empty()) {
      auto loaded = load_colour_model(settings.colours);
      if (!loaded) return std::unexpected(loaded.error().to_string());
      colour_model = std::move(*loaded);
    }
    const SourceRequest request{*rig, *layouts, objects, colour_model, scene.settings.headset.refresh_hz};
    // One pool of the settings' threads for the whole tracker: the video cameras' detection and
    // the tracking stages take turns on it.
    std::shared_ptr<JobPool> jobs;
    if (const int threads = threads_or_all(settings.threads); threads > 1) jobs = std::make_shared<JobPool>(threads);
    auto opened = open_frame_source(settings, rig_file, request, custom, jobs);
    if (!opened) return std::unexpected(opened.error());
    LiveTrackingSettings live_settings;
    live_settings.filter_hands = settings.filter_hands;
    live_settings.filter_hand_frames = settings.filter_hand_frames;
    live_settings.threads = 1;
    live_settings.jobs = jobs;
    live_settings.tracker_rig = std::move(opened->tracker_rig);
    auto live = std::make_unique<LiveTracking>(std::move(opened->source), objects, *layouts, live_settings);
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
  rs.publish_hands = settings.publish_hands;
  rs.world_from_stage = settings.world_from_stage;
  auto runtime = Runtime::create(scene, renderer, rs, make_tracking);
  if (!runtime) return std::unexpected(runtime.error());
  launched->runtime_ = std::move(*runtime);
  return launched;
}

}  // namespace rhot
