// rhot-eval colour: coloured markers end to end on simulated colour cameras. The demo's script
// (its hands with the colour layouts, its star-tracked objects with blue stars) is drawn by the
// renderer for each camera of the rig (engine/sim/ColourCameras.h) with the scene's objects as
// clutter, noise, blur and a white balance; each image goes through a colour detector per camera
// (regions of interest from the frame before), then matching, stars and hands as in the demo.
//
// Against the truth: per camera and frame, an identity render tells each marker's visible pixels.
//   detection_rate            markers visible by 20 pixels or more that have a detection of their
//                             colour within their projected radius + 1 px of their centre
//   false_detections_per_image  detections near no visible marker of their colour
//   centroid_rms_px           detection to the marker centre's projection, for markers at least
//                             90 % visible (a partly hidden sphere's centroid moves, rightly)
//   fingertip_mean_mm         tracked fingertip joints to the true ones, frames with the hand seen
//   detect_median_ms          one image through the detector as the demo runs it (tracked), and
//                             detect_full_median_ms for a whole-image search of the same images
//   hand_seen_fraction        hands seen (their frame found: by their star, or by the markers left
//                             while it is hidden) per hand and frame
//   hand_in_view_fraction     hands whose wrist and true fingertips lie inside every image, likewise
//   misplaced_hand_frames     hands seen with their frame 5 cm or more from the true one (a count
//                             per hand and frame)
// Every 90 frames a line on stderr gives the same per hand over those frames, with the markers of
// its star and its fingertips visible by 20 pixels in every image (means).
//
// Without --colours the default model is used with its white reference taken from the scene under
// daylight (6500 K), as rhot-calib colours would take it; --white-balance-k then changes the light.

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <expected>
#include <iostream>
#include <map>

#include <filesystem>

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>
#include <opencv2/imgproc.hpp>

#include "base/Jobs.h"
#include "engine/core/World.h"
#include "engine/hand/HandComponents.h"
#include "engine/scene/SceneLoader.h"
#include "engine/sim/ColourCameras.h"
#include "engine/sim/Demo.h"
#include "engine/tracked/LiveTracking.h"
#include "tools/eval/Eval.h"
#include "tracking/camera/RigFile.h"
#include "tracking/media/Media.h"
#include "tracking/core/MarkerColour.h"
#include "tracking/hand/HandJoints.h"

namespace rhot::eval {

namespace {

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

struct Counts {
  long visible = 0, found = 0, false_detections = 0, centroid_n = 0;
  double centroid_sum2 = 0.0;
  nlohmann::ordered_json json(long images) const {
    nlohmann::ordered_json j;
    j["visible_markers"] = visible;
    j["detection_rate"] = visible > 0 ? static_cast<double>(found) / static_cast<double>(visible) : 0.0;
    j["false_detections_per_image"] = images > 0 ? static_cast<double>(false_detections) / static_cast<double>(images) : 0.0;
    j["centroid_rms_px"] = centroid_n > 0 ? std::sqrt(centroid_sum2 / static_cast<double>(centroid_n)) : 0.0;
    j["centroid_samples"] = centroid_n;
    return j;
  }
};

// What the frames count.
struct ColourTally {
  Counts all;
  std::map<int, Counts> per_colour;
  std::vector<double> detect_ms, detect_full_ms;
  double tip_sum_m = 0.0;
  long tips = 0, hand_frames = 0, hands_seen = 0, hands_in_view = 0, hands_misplaced = 0;
  long images = 0;
  // The same since the last progress line, per hand (left, right).
  std::array<double, 2> window_tip_sum_m{};
  std::array<long, 2> window_tips{}, window_frames{}, window_seen{}, window_in_view{}, window_star_markers{}, window_tip_markers{};
};

// One progress line: per hand over the window, the frames with the hand in view (its wrist and
// true fingertips inside every image), its star's markers visible by 20 pixels in every image (a
// mean), the frames with the hand seen and the fingertips' error; then the window is reset.
std::string window_summary(ColourTally& tally) {
  std::string out;
  for (std::size_t h = 0; h < 2; ++h) {
    const auto per_frame = [&](long count) {
      return tally.window_frames[h] > 0 ? static_cast<double>(count) / static_cast<double>(tally.window_frames[h]) : 0.0;
    };
    const double tip_mm = tally.window_tips[h] > 0 ? 1000.0 * tally.window_tip_sum_m[h] / static_cast<double>(tally.window_tips[h]) : 0.0;
    out += fmt::format(
        "{}{} hand in view {:.2f}, markers in every image: star {:.1f}, fingertips {:.1f}; seen {:.2f}, fingertips {:.1f} mm",
        h == 0 ? "" : "; ", h == 0 ? "left" : "right", per_frame(tally.window_in_view[h]), per_frame(tally.window_star_markers[h]),
        per_frame(tally.window_tip_markers[h]), per_frame(tally.window_seen[h]), tip_mm);
    tally.window_tip_sum_m[h] = 0.0;
    tally.window_tips[h] = tally.window_frames[h] = tally.window_seen[h] = tally.window_in_view[h] = tally.window_star_markers[h] =
        tally.window_tip_markers[h] = 0;
  }
  return out;
}

// --colours' model, or the default one without it: false after saying what was wrong.
bool load_model(const ColourArgs& a, ColourModel& model) {
  model = default_colour_model();
  if (!a.colours_file.empty()) {
    auto loaded = load_colour_model(a.colours_file);
    if (!loaded) {
      std::cerr << "rhot-eval: " << loaded.error().to_string() << "\n";
      return false;
    }
    model = std::move(*loaded);
  }
  return true;
}

// The default model's white reference as a user's rhot-calib colours would take it: the scene
// under daylight (6500 K), its first frame's images. False after saying what was wrong.
bool take_daylight_white(const ColourArgs& a, const CameraRig& rig, const SceneDesc& scene, const ColourCameraSettings& cs,
                         const DemoSimulation& sim, ColourModel& model) {
  auto daylight = ColourCameras::create(rig, scene, cs);
  if (!daylight) {
    std::cerr << "rhot-eval: " << daylight.error() << "\n";
    return false;
  }
  const auto images = (*daylight)->render(sim.world->colour_shot(sim.world->at(a.start_s)), 0);
  std::array<double, 3> sum{};
  for (const cv::Mat& image : images) {
    const auto m = median_colour(image);
    for (std::size_t ch = 0; ch < 3; ++ch) sum[ch] += m[ch] / static_cast<double>(images.size());
  }
  model.white_reference = sum;
  return true;
}

// --pictures: each camera's image with its detections circled, and what the model classifies in
// it. False after saying what could not be written.
bool write_pictures(const ColourArgs& a, const RigFrame& frame, const ColourCameraSource& src, const ColourModel& model) {
  std::filesystem::create_directories(a.pictures_dir);
  for (std::size_t c = 0; c < frame.cameras.size(); ++c) {
    const std::string base = a.pictures_dir + "/cam" + std::to_string(c);
    cv::Mat annotated = src.last_images()[c].clone();
    for (const Detection& d : frame.cameras[c].detections) {
      cv::circle(annotated, cv::Point(static_cast<int>(std::lround(d.pixel.x())), static_cast<int>(std::lround(d.pixel.y()))), 9,
                 cv::Scalar(255, 255, 255), 1, cv::LINE_AA);
    }
    auto written = write_image(base + ".png", annotated);
    if (written) written = write_image(base + "_colours.png", classification_picture(ColourTable(model), src.last_images()[c]));
    if (!written) {
      std::cerr << "rhot-eval: " << written.error() << "\n";
      return false;
    }
  }
  return true;
}

// The markers of one image visible by 20 pixels or more: found when a detection of their colour
// lies within their projected radius + 1 px; `used` marks the detections that found one.
void count_found(const ColourShot& shot, const std::vector<MarkerView>& v, const std::vector<Detection>& dets, std::vector<bool>& used,
                 ColourTally& tally) {
  for (std::size_t m = 0; m < shot.markers.size(); ++m) {
    if (!v[m].in_front || v[m].visible_px < 20) continue;
    const int colour_index = shot.markers[m].colour;
    Counts& pc = tally.per_colour[colour_index];
    ++tally.all.visible;
    ++pc.visible;
    const double reach = std::sqrt(v[m].disc_px / 3.14159265358979) + 1.0;
    int best = -1;
    double best_d = reach;
    for (std::size_t d = 0; d < dets.size(); ++d) {
      const double dist = (dets[d].pixel - v[m].pixel).norm();
      if (dets[d].colour == colour_index && dist < best_d) best_d = dist, best = static_cast<int>(d);
    }
    if (best < 0) continue;
    used[static_cast<std::size_t>(best)] = true;
    ++tally.all.found;
    ++pc.found;
    if (v[m].visible_px >= 0.9 * v[m].disc_px) {
      tally.all.centroid_sum2 += best_d * best_d;
      pc.centroid_sum2 += best_d * best_d;
      ++tally.all.centroid_n;
      ++pc.centroid_n;
    }
  }
}

// A detection near no visible marker of its colour (any visible pixel at all) is false.
void count_false(const ColourShot& shot, const std::vector<MarkerView>& v, const std::vector<Detection>& dets,
                 const std::vector<bool>& used, ColourTally& tally) {
  for (std::size_t d = 0; d < dets.size(); ++d) {
    if (used[d]) continue;
    bool near = false;
    for (std::size_t m = 0; m < shot.markers.size() && !near; ++m) {
      if (!v[m].in_front || v[m].visible_px == 0 || shot.markers[m].colour != dets[d].colour) continue;
      near = (dets[d].pixel - v[m].pixel).norm() < std::sqrt(v[m].disc_px / 3.14159265358979) + 2.0;
    }
    if (!near) {
      ++tally.all.false_detections;
      ++tally.per_colour[dets[d].colour].false_detections;
    }
  }
}

// Each camera's image of the frame: timed through a whole-image search, and its detections
// against the markers the identity render shows.
void count_detections(const RigFrame& frame, const ColourShot& shot, const std::vector<std::vector<MarkerView>>& views,
                      const ColourCameraSource& src, ColourDetector& full_detector, ColourTally& tally) {
  for (std::size_t c = 0; c < frame.cameras.size(); ++c) {
    ++tally.images;
    const auto start = std::chrono::steady_clock::now();
    (void)full_detector.detect(src.last_images()[c]);
    tally.detect_full_ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
    const auto& dets = frame.cameras[c].detections;
    std::vector<bool> used(dets.size(), false);
    count_found(shot, views[c], dets, used, tally);
    count_false(shot, views[c], dets, used, tally);
  }
}

// The tracked fingertips against the true ones, for the hands seen.
void count_fingertips(LiveTracking& live, const DemoWorld& world, const CameraRig& rig, const std::vector<std::vector<MarkerView>>& views,
                      ColourTally& tally) {
  const auto truth = world.truth();
  std::size_t first_marker = 0;  // the hand's markers in the shot: the left layout's, then the right's
  for (std::size_t h = 0; h < 2 && truth; ++h) {
    // Its hand star's four markers (layout_markers' first), then its fingertip markers, visible
    // by 20 pixels in every image.
    const std::size_t markers = layout_marker_colours(live.layouts()[h]).size();
    for (std::size_t m = first_marker; m < first_marker + std::min<std::size_t>(markers, 4 + kFingerCount); ++m) {
      const bool everywhere = std::all_of(views.begin(), views.end(), [&](const std::vector<MarkerView>& v) {
        return m < v.size() && v[m].in_front && v[m].visible_px >= 20;
      });
      (m < first_marker + 4 ? tally.window_star_markers : tally.window_tip_markers)[h] += everywhere ? 1 : 0;
    }
    first_marker += markers;
    ++tally.hand_frames;
    ++tally.window_frames[h];
    // In view: the wrist and every true fingertip inside every camera's image.
    bool in_view = true;
    for (const Camera& camera : rig.cameras) {
      const CameraProjection projection(camera);
      for (const HandJoint j : {HandJoint::kWrist, HandJoint::kThumbTip, HandJoint::kIndexTip, HandJoint::kMiddleTip, HandJoint::kRingTip,
                                HandJoint::kLittleTip}) {
        const auto pixel =
            projection.project(truth->hands[h].world_from_hand * truth->hands[h].pose.position_m[static_cast<std::size_t>(j)]);
        in_view = in_view && pixel && projection.in_image(*pixel);
      }
    }
    tally.window_in_view[h] += in_view ? 1 : 0;
    tally.hands_in_view += in_view ? 1 : 0;
    const TrackedHand& hand = live.tracked_hand(h == 0 ? HandSide::kLeft : HandSide::kRight);
    if (!hand.hand_seen) continue;
    ++tally.hands_seen;
    // Seen, but its frame 5 cm or more from the true one: another constellation taken for its star.
    if ((hand.world_from_hand.translation - truth->hands[h].world_from_hand.translation).norm() >= 0.05) ++tally.hands_misplaced;
    ++tally.window_seen[h];
    for (int k = 0; k < kFingerCount; ++k) {
      const auto tip = static_cast<std::size_t>(chain_joints(static_cast<Finger>(k))[3]);
      const double error_m = (hand.joints_world[tip] - truth->hands[h].world_from_hand * truth->hands[h].pose.position_m[tip]).norm();
      tally.tip_sum_m += error_m;
      ++tally.tips;
      tally.window_tip_sum_m[h] += error_m;
      ++tally.window_tips[h];
    }
  }
}

// The JSON rhot-eval colour prints, in this order.
nlohmann::ordered_json report(const ColourArgs& a, const std::string& device_name, const ColourTally& tally) {
  nlohmann::ordered_json j;
  j["rig"] = a.rig_file;
  j["frames"] = a.frames;
  j["images"] = tally.images;
  j["device"] = device_name;
  j["noise"] = a.noise;
  j["white_balance_k"] = a.kelvin;
  j["clutter"] = a.clutter;
  j["threads"] = threads_or_all(a.threads);
  const nlohmann::ordered_json overall = tally.all.json(tally.images);
  for (auto it = overall.begin(); it != overall.end(); ++it) j[it.key()] = it.value();
  j["fingertip_mean_mm"] = tally.tips > 0 ? 1000.0 * tally.tip_sum_m / static_cast<double>(tally.tips) : 0.0;
  j["hand_seen_fraction"] = tally.hand_frames > 0 ? static_cast<double>(tally.hands_seen) / static_cast<double>(tally.hand_frames) : 0.0;
  j["hand_in_view_fraction"] =
      tally.hand_frames > 0 ? static_cast<double>(tally.hands_in_view) / static_cast<double>(tally.hand_frames) : 0.0;
  j["misplaced_hand_frames"] = tally.hands_misplaced;
  j["detect_median_ms"] = median(tally.detect_ms);
  j["detect_full_median_ms"] = median(tally.detect_full_ms);
  nlohmann::ordered_json colours;
  for (const auto& [c, counts] : tally.per_colour) colours[std::string(marker_colour_name(c))] = counts.json(tally.images);
  j["per_colour"] = colours;
  return j;
}

// --drawn: the demo's runtime (tracking, physics, grasps, hidden digits placed against what a hand
// holds or carries: engine/interact/FingerContact.h) on the same script and colour cameras, the
// physical hands (HandBody's joints: what the renderer draws, before it predicts them forward to the
// display's time) against the truth at the frame's capture, beside the tracked hands of the same
// frames. The runtime's colour model is the demo's (rhot's six colours, no white
// reference taken, or --colours), so its detections may differ a little from the pass above.
std::expected<nlohmann::ordered_json, std::string> drawn_fingertips(const ColourArgs& a, const SceneDesc& scene) {
  DemoSettings settings;
  settings.asset_dir = RHOT_ASSET_DIR;
  settings.colour_markers = true;
  settings.rig_file = a.rig_file;
  if (!a.colours_file.empty()) settings.colours = a.colours_file;
  settings.colour_cameras.noise_sigma = a.noise;
  settings.colour_cameras.clutter = a.clutter;
  settings.colour_cameras.kelvin = a.kelvin;
  settings.colour_cameras.device = a.device;
  settings.seed = a.seed;
  settings.threads = a.threads;
  auto created = Demo::create(scene, nullptr, settings);
  if (!created) return std::unexpected(created.error());
  Demo& demo = **created;
  struct Sums {
    double tracked_m = 0.0, drawn_m = 0.0;
    long tips = 0;
    void add(double tracked, double drawn) {
      tracked_m += tracked;
      drawn_m += drawn;
      ++tips;
    }
    double tracked_mm() const { return tips > 0 ? 1000.0 * tracked_m / static_cast<double>(tips) : 0.0; }
    double drawn_mm() const { return tips > 0 ? 1000.0 * drawn_m / static_cast<double>(tips) : 0.0; }
  };
  Sums all, hidden, window;
  long hand_frames = 0;
  const double rate_hz = scene.settings.headset.refresh_hz;
  for (int f = 0; f < a.frames; ++f) {
    const double t = a.start_s + f / rate_hz;
    // The truth the cameras photograph, before the frame's own stages (the look stage re-aims the script).
    const SceneTruth truth = demo.simulated()->truth_at(t);
    demo.runtime().run_frame(t);
    demo.world().view<Hand, HandBody>().each([&](Entity, Hand& hand, HandBody& body) {
      const std::size_t h = hand.side == HandSide::kLeft ? 0 : 1;
      const TrackedHand& tracked = demo.live()->tracked_hand(hand.side);
      if (!tracked.hand_seen || !body.active || h >= truth.hands.size()) return;
      ++hand_frames;
      for (int k = 0; k < kFingerCount; ++k) {
        const auto tip = static_cast<std::size_t>(chain_joints(static_cast<Finger>(k))[3]);
        const Eigen::Vector3d truth_m = truth.hands[h].world_from_hand * truth.hands[h].pose.position_m[tip];
        const double tracked_m = (tracked.joints_world[tip] - truth_m).norm();
        const double drawn_m = (body.joints_world[tip] - truth_m).norm();
        all.add(tracked_m, drawn_m);
        window.add(tracked_m, drawn_m);
        if (!tracked.state.tip_seen[static_cast<std::size_t>(k)]) hidden.add(tracked_m, drawn_m);
      }
    });
    if ((f + 1) % 90 == 0 || f + 1 == a.frames) {
      std::cerr << fmt::format(
          "rhot-eval colour --drawn: {}/{} frames (t = {:.1f} s; since the last line: fingertips tracked {:.1f} mm, drawn {:.1f} mm)\n",
          f + 1, a.frames, t, window.tracked_mm(), window.drawn_mm());
      window = {};
    }
  }
  nlohmann::ordered_json j;
  j["drawn_fingertip_mean_mm"] = all.drawn_mm();
  j["drawn_tracked_fingertip_mean_mm"] = all.tracked_mm();
  j["drawn_hidden_fingertip_mean_mm"] = hidden.drawn_mm();
  j["drawn_tracked_hidden_fingertip_mean_mm"] = hidden.tracked_mm();
  j["drawn_hand_frames"] = hand_frames;
  return j;
}

}  // namespace

int colour(const ColourArgs& a) {
  spdlog::set_default_logger(spdlog::stderr_color_mt("rhot-eval"));  // stdout is the JSON
  const auto scene = load_scene_file(a.scene_file);
  if (!scene) {
    std::cerr << "rhot-eval: " << scene.error().to_string() << "\n";
    return 1;
  }
  const auto rig = load_rig(a.rig_file);
  if (!rig) {
    std::cerr << "rhot-eval: " << rig.error() << "\n";
    return 1;
  }
  ColourModel model;
  if (!load_model(a, model)) return 1;
  auto sim = make_demo_simulation(*scene, RHOT_ASSET_DIR, {}, 0, true);
  if (!sim) {
    std::cerr << "rhot-eval: " << sim.error() << "\n";
    return 1;
  }
  ColourCameraSettings cs;
  cs.noise_sigma = a.noise;
  cs.clutter = a.clutter;
  cs.device = a.device;
  cs.seed = a.seed;
  if (a.colours_file.empty() && !take_daylight_white(a, *rig, *scene, cs, *sim, model)) return 1;
  cs.kelvin = a.kelvin;
  auto cameras = ColourCameras::create(*rig, *scene, cs);
  if (!cameras) {
    std::cerr << "rhot-eval: " << cameras.error() << "\n";
    return 1;
  }
  ColourCameras* cams = cameras->get();
  std::shared_ptr<DemoWorld> world = sim->world;
  auto source = std::make_unique<ColourCameraSource>(
      std::move(*cameras), [world](double t) { return world->colour_shot(world->at(t)); }, model);
  ColourCameraSource* src = source.get();
  LiveTrackingSettings live_settings;
  live_settings.threads = a.threads;
  LiveTracking live(std::move(source), sim->objects, sim->layouts, live_settings);
  ColourDetector full_detector(model);

  ColourTally tally;
  const double rate_hz = scene->settings.headset.refresh_hz;
  for (int f = 0; f < a.frames; ++f) {
    const double t = a.start_s + f / rate_hz;
    live.read_source(t);
    live.match();
    live.track_stars(t);
    live.track_hands(t);
    const ColourShot& shot = src->last_shot();
    const auto views = cams->marker_visibility(shot);
    const RigFrame& frame = live.frame();
    if (f == 0 && !a.pictures_dir.empty() && !write_pictures(a, frame, *src, model)) return 1;
    tally.detect_ms.push_back(src->last_detect_ms() / static_cast<double>(frame.cameras.size()));
    count_detections(frame, shot, views, *src, full_detector, tally);
    count_fingertips(live, *world, *rig, views, tally);
    if ((f + 1) % 90 == 0 || f + 1 == a.frames)
      std::cerr << "rhot-eval colour: " << (f + 1) << "/" << a.frames << " frames (t = " << fmt::format("{:.1f}", t)
                << " s; since the last line: " << window_summary(tally) << ")\n";
  }
  nlohmann::ordered_json j = report(a, cams->renderer_info().device_name, tally);
  if (a.drawn) {
    const auto drawn = drawn_fingertips(a, *scene);
    if (!drawn) {
      std::cerr << "rhot-eval: " << drawn.error() << "\n";
      return 1;
    }
    for (auto it = drawn->begin(); it != drawn->end(); ++it) j[it.key()] = it.value();
  }
  std::cout << j.dump(2) << "\n";
  return 0;
}

}  // namespace rhot::eval
