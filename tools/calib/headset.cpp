// rhot-calib headset: the rig registered to a headset's STAGE space (tracking/calib/HeadsetRegistration.h).
// A marker star fixed on the headset is tracked by the rig while the headset's OpenXR runtime says
// where the head is; the user looks around for half a minute. With --simulate the rig is the
// simulated one and the star rides on the runtime's own (moving) head through a known transform,
// so the result is checked against the truth.

#include <chrono>
#include <cmath>
#include <memory>
#include <numbers>
#include <optional>
#include <thread>

#include <glm/glm.hpp>

#include "base/SteadyClock.h"
#include "engine/render/Renderer.h"
#include "engine/render/XrHeadset.h"
#include "tools/calib/Calib.h"
#include "tracking/calib/HeadsetRegistration.h"
#include "tracking/camera/RigFile.h"
#include "tracking/geometry/Matching.h"
#include "tracking/rigid/StarSet.h"
#include "tracking/rigid/StarTracker.h"
#include "tracking/sim/SimulatedRig.h"

namespace rhot::calib_tool {

namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

struct HeadsetOptions {
  bool simulate = false;
  std::string rig = std::string(RHOT_ASSET_DIR) + "/rigs/seated-4.yaml";
  std::string stars = std::string(RHOT_ASSET_DIR) + "/stars/seed-case.json";
  int star = -1;  // -1: the set's first
  std::string source;
  int blob_threshold = -1;
  NodeKeyFlags keys;
  double seconds = 30.0;
  double sigma_px = 0.5;
  unsigned seed = 1;
  std::string out;
  std::string pictures;
  bool json = false;
};

Rigid3d rigid_from(const glm::mat4& m) {
  Eigen::Matrix3d r;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) r(i, j) = static_cast<double>(m[j][i]);
  }
  Rigid3d out;
  out.rotation = Eigen::Quaterniond(r).normalized();
  out.translation = Eigen::Vector3d(static_cast<double>(m[3][0]), static_cast<double>(m[3][1]), static_cast<double>(m[3][2]));
  return out;
}

// The point the rig's cameras look at: nearest, in least squares, to every camera's optical axis.
Eigen::Vector3d rig_aim(const CameraRig& rig) {
  Eigen::Matrix3d a = Eigen::Matrix3d::Zero();
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
  for (const Camera& c : rig.cameras) {
    const Eigen::Vector3d d = (c.cam_from_world.rotation.conjugate() * Eigen::Vector3d::UnitZ()).normalized();
    const Eigen::Matrix3d p = Eigen::Matrix3d::Identity() - d * d.transpose();
    a += p;
    b += p * c.centre_world();
  }
  return a.ldlt().solve(b);
}

// The simulation's truth: the stage turned 25 degrees and moved so that the runtime's head
// (about 1.6 m above its floor) is where the rig looks; the star 7.5 cm above the head, 4 cm to
// the front, tilted 10 degrees.
struct Truth {
  Rigid3d world_from_stage;
  Rigid3d head_from_star;
};
Truth simulated_truth(const CameraRig& rig) {
  Truth t;
  t.world_from_stage.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(25.0 * kDeg, Eigen::Vector3d::UnitY()));
  t.world_from_stage.translation = rig_aim(rig) - t.world_from_stage.rotation * Eigen::Vector3d(0.0, 1.6, 0.0);
  t.head_from_star.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(10.0 * kDeg, Eigen::Vector3d::UnitX()));
  t.head_from_star.translation = Eigen::Vector3d(0.0, 0.075, -0.04);
  return t;
}

// One frame of the rig: the simulated cameras seeing the star where the runtime's head puts it, or
// the real source's next frame.
struct Rig {
  CameraRig cameras;
  std::unique_ptr<SimulatedRig> simulated;
  std::unique_ptr<FrameSource> source;
  Rigid3d head;  // the simulated star rides on this (set before each simulated frame)
};

// Collects samples on the headset until `seconds` of them (or Ctrl-C); the session is then ended.
std::vector<HeadsetPoseSample> collect(const HeadsetOptions& o, XrHeadset& headset, Renderer& renderer, Rig& rig, const MarkerStar& star) {
  StarSet only;
  only.stars.push_back(star);
  StarTracker tracker{StarLibrary(only)};
  PixelSigmaEstimate pixel_sigma;
  const RigMatcher matcher(rig.cameras);
  std::vector<HeadsetPoseSample> samples;
  const double start_s = steady_now_s();
  double first_s = std::nan(""), last_report_s = start_s, max_turn_deg = 0.0;
  bool asked_to_end = false;
  while (!headset.should_exit()) {
    headset.poll_events();
    const double now = steady_now_s();
    if (!asked_to_end && (stop_asked() || (std::isfinite(first_s) && now - first_s >= o.seconds) ||
                          (!std::isfinite(first_s) && now - start_s > o.seconds + 15.0))) {
      headset.request_exit();
      asked_to_end = true;
    }
    if (!headset.session_running() || !headset.begin_frame()) {
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
      if (asked_to_end && steady_now_s() - now > 5.0) break;
      continue;
    }
    // The rig's frame, and the head where the runtime has it at the frame's exposure.
    std::optional<RigFrame> frame;
    double capture_s = steady_now_s();
    const auto head_now = headset.stage_from_head(capture_s);
    if (rig.simulated) {
      if (head_now) rig.head = rigid_from(*head_now);
      frame = rig.simulated->next(capture_s - start_s);
    } else {
      frame = rig.source->next(capture_s - start_s);
      if (frame && std::isfinite(frame->capture_steady_s)) capture_s = frame->capture_steady_s;
    }
    const auto head = rig.simulated ? head_now : headset.stage_from_head(capture_s);
    if (frame && head) {
      const std::vector<MatchedPoint> matched = matcher.match(*frame, match_settings_for(pixel_sigma.sigma_px()));
      std::vector<Eigen::Vector3d> points;
      for (const MatchedPoint& m : matched) points.push_back(m.point.position_world);
      const std::vector<double> sigmas = point_sigmas_m(matched, pixel_sigma.update(matched));
      const TrackedStar& tracked = tracker.update(frame->time_s, points, sigmas).front();
      // This frame's own fit: the filtered pose lags a turning head.
      if (tracked.measured_now()) {
        if (!std::isfinite(first_s)) first_s = capture_s;
        samples.push_back({capture_s - first_s, tracked.measured, rigid_from(*head)});
        max_turn_deg = std::max(max_turn_deg,
                                samples.front().stage_from_head.rotation.angularDistance(samples.back().stage_from_head.rotation) / kDeg);
      }
    }
    const auto views = headset.locate_views(0.05, 100.0);
    FrameInput drawn;
    if (views) drawn.views = *views;
    renderer.render(drawn);  // ends the headset's frame
    if (now - last_report_s >= 5.0) {
      spdlog::info("{} samples, the head turned up to {:.1f} degrees from the first", samples.size(), max_turn_deg);
      last_report_s = now;
    }
  }
  renderer.finish();
  return samples;
}

nlohmann::json rigid_json(const Rigid3d& r) {
  const Eigen::AngleAxisd aa(r.rotation);
  return {{"translation_m", {r.translation.x(), r.translation.y(), r.translation.z()}},
          {"rotation_deg", aa.angle() / kDeg},
          {"axis", {aa.axis().x(), aa.axis().y(), aa.axis().z()}}};
}

// The rig: the simulated one (its star's markers scripted by the caller), or the real source.
std::expected<Rig, std::string> open_rig(const HeadsetOptions& o) {
  auto loaded = load_rig(o.rig);
  if (!loaded) return std::unexpected(loaded.error());
  Rig rig;
  rig.cameras = *loaded;
  if (o.simulate) {
    SimulatedRigSettings settings;
    settings.sigma_px = o.sigma_px;
    settings.seed = o.seed;
    rig.simulated = std::make_unique<SimulatedRig>(rig.cameras, std::vector<Trajectory>{}, settings);
    return rig;
  }
  auto source = open_frame_source(rig.cameras, o.source, o.blob_threshold, o.keys);
  if (!source) return std::unexpected(source.error());
  rig.source = std::move(*source);
  return rig;
}

int run(const HeadsetOptions& o) {
  if (o.simulate == !o.source.empty()) return fail("give either --simulate or --source (the cameras that see the headset's star)");
  const auto set = load_star_set(o.stars);
  if (!set) return fail(set.error());
  if (set->stars.empty()) return fail(o.stars + ": no star in the set");
  const MarkerStar* star = &set->stars.front();
  if (o.star >= 0) {
    star = nullptr;
    for (const MarkerStar& s : set->stars) star = s.id == o.star ? &s : star;
    if (star == nullptr) return fail("--star " + std::to_string(o.star) + ": no star of that id in " + o.stars);
  }
  auto headset = XrHeadset::create({"rhot-calib", false});
  if (!headset) return fail("headset: " + headset.error());
  RendererSettings render;
  auto renderer = Renderer::create(render, nullptr, headset->get());
  if (!renderer) return fail("headset: cannot start the renderer: " + renderer.error());

  auto rig = open_rig(o);
  if (!rig) return fail(rig.error());
  std::optional<Truth> truth;
  if (rig->simulated) {
    truth = simulated_truth(rig->cameras);
    Rig* r = &*rig;
    const Truth t = *truth;
    const MarkerStar s = *star;
    rig->simulated->set_scripted_markers([r, t, s](double) {
      const Rigid3d world_from_star = t.world_from_stage * r->head * t.head_from_star;
      std::vector<Eigen::Vector3d> markers;
      for (const Eigen::Vector3d& m : s.markers_mm) markers.push_back(world_from_star * (m * 1e-3));
      return markers;
    });
  }
  stop_on_signals();
  spdlog::info("look around for {:.0f} s with the headset on, turning and tilting the head (Ctrl-C ends early)", o.seconds);
  const std::vector<HeadsetPoseSample> samples = collect(o, **headset, **renderer, *rig, *star);
  const auto registration = register_headset(samples);
  if (!registration) return fail("headset: " + registration.error());
  make_parent_folder(o.out);
  if (const auto written = write_headset_registration(o.out, *registration); !written) return fail(written.error());
  const std::filesystem::path picture = pictures_dir(o.pictures, o.out) / "headset_residuals.png";
  if (const auto drawn = write_registration_picture(picture, samples, *registration); !drawn) return fail(drawn.error());
  spdlog::info("{}: {} samples, residual {:.2f} mm / {:.3f} degrees RMS; picture {}", o.out, registration->samples, registration->rms_mm,
               registration->rms_deg, picture.string());
  nlohmann::json report{{"out", o.out},
                        {"samples", registration->samples},
                        {"rms_mm", registration->rms_mm},
                        {"rms_deg", registration->rms_deg},
                        {"turn_deg", registration->turn_deg},
                        {"second_axis_ratio", registration->second_axis_ratio},
                        {"world_from_stage", rigid_json(registration->world_from_stage)},
                        {"head_from_star", rigid_json(registration->head_from_star)},
                        {"picture", picture.string()}};
  if (truth) {
    const auto err = [](const Rigid3d& a, const Rigid3d& b) {
      return nlohmann::json{{"rotation_deg", a.rotation.angularDistance(b.rotation) / kDeg},
                            {"translation_mm", 1e3 * (a.translation - b.translation).norm()}};
    };
    report["truth_error"] = {{"world_from_stage", err(registration->world_from_stage, truth->world_from_stage)},
                             {"head_from_star", err(registration->head_from_star, truth->head_from_star)}};
    spdlog::info("against the simulation's truth: the stage off by {:.3f} degrees and {:.2f} mm",
                 report["truth_error"]["world_from_stage"]["rotation_deg"].get<double>(),
                 report["truth_error"]["world_from_stage"]["translation_mm"].get<double>());
  }
  if (o.json) print_json(report);
  return 0;
}

}  // namespace

void add_headset(CLI::App& app, int& exit_code) {
  auto o = std::make_shared<HeadsetOptions>();
  CLI::App* cmd = app.add_subcommand(
      "headset", "register the rig to a headset's space from a marker star on the headset, through its OpenXR runtime (docs/openxr.md)");
  cmd->add_flag("--simulate", o->simulate, "the simulated rig, seeing a star on the runtime's own moving head (the truth is known)");
  cmd->add_option("--rig", o->rig, "the calibrated rig (OpenCV YAML)")->capture_default_str();
  cmd->add_option("--source", o->source, "the cameras: video:DEV[,DEV...] or nodes:NAME@ENDPOINT[,...] (as rhot-demo)");
  add_node_key_flags(*cmd, o->keys);
  cmd->add_option("--stars", o->stars, "the marker star set (JSON)")->capture_default_str();
  cmd->add_option("--star", o->star, "the id of the star on the headset (default: the set's first)")->check(CLI::Range(0, 1000000));
  cmd->add_option("--seconds", o->seconds, "how long to sample once the star is seen")
      ->capture_default_str()
      ->check(CLI::Range(1.0, 3600.0) & finite_number());
  cmd->add_option("--sigma", o->sigma_px, "with --simulate: pixel noise")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 10.0) & finite_number());
  cmd->add_option("--seed", o->seed, "with --simulate: noise seed")->capture_default_str();
  cmd->add_option("--blob-threshold", o->blob_threshold, "with video: grey level of a marker pixel (-1: automatic)")
      ->capture_default_str()
      ->check(CLI::Range(-1, 255));
  cmd->add_option("--out", o->out, "the registration to write (OpenCV YAML; rhot-demo --xr --registration FILE reads it)")->required();
  cmd->add_option("--pictures", o->pictures, "folder for headset_residuals.png (default: --out's folder)");
  cmd->add_flag("--json", o->json, "print a JSON report on stdout");
  cmd->callback([o, &exit_code] { exit_code = run(*o); });
}

}  // namespace rhot::calib_tool
