// rhot-eval frame: the demo's whole frame headless, every stage timed (engine/sim/Demo.h).

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <limits>
#include <numbers>
#include <optional>
#include <string>
#include <vector>

#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>
#include <Eigen/Dense>
#include <nlohmann/json.hpp>

#include "base/Jobs.h"
#include "engine/sim/GraspScenarios.h"
#include "engine/scene/SceneLoader.h"
#include "tracking/camera/RigFile.h"
#include "tracking/geometry/Matching.h"
#include "tracking/sim/HandMotions.h"
#include "tracking/hand/HandTracker.h"
#include "tracking/rigid/StarTracker.h"
#include "tracking/sim/SimulatedRig.h"

#include "engine/app/FrameLoop.h"
#include "engine/render/XrHeadset.h"
#include "engine/runtime/HeadsetLoop.h"
#include "engine/sim/Demo.h"
#include "tools/eval/Eval.h"

namespace rhot::eval {

namespace {

// The drawn hands and objects against the truth, at capture and at display (engine/sim/Demo.h).
nlohmann::json prediction_errors_json(const rhot::PredictionErrors& errors) {
  nlohmann::json j = {{"joint_samples", errors.joints},
                      {"at_capture_mean_mm", 1e3 * errors.at_capture_mean_m()},
                      {"at_display_mean_mm", 1e3 * errors.predicted_at_display_mean_m()},
                      {"at_display_unpredicted_mean_mm", 1e3 * errors.tracked_at_display_mean_m()},
                      {"ratio_unpredicted", errors.ratio_without_prediction()},
                      {"horizon_mean_ms", errors.joints > 0 ? 1e3 * errors.horizon_sum_s / static_cast<double>(errors.joints) : 0.0}};
  if (errors.objects > 0) {
    const auto n = static_cast<double>(errors.objects);
    j["objects"] = {{"samples", errors.objects},
                    {"at_capture_mean_mm", 1e3 * errors.object_at_capture_sum_m / n},
                    {"at_display_mean_mm", 1e3 * errors.object_predicted_at_display_sum_m / n},
                    {"at_display_unpredicted_mean_mm", 1e3 * errors.object_tracked_at_display_sum_m / n}};
  }
  return j;
}

}  // namespace

// The demo's whole frame, headless: simulated cameras, tracking, physics and both eyes rendered
// offscreen, every stage timed (engine/sim/Demo.h).
int frame(const std::string& scene_file, const std::string& eye, int frames, const std::string& device, rhot::Shading shading,
          const WorldFlags& world_flags, const FrameOptions& options) {
  // stdout carries the JSON only: the log goes to stderr.
  spdlog::set_default_logger(spdlog::stderr_color_mt("rhot-eval"));
  const auto scene = rhot::load_scene_file(scene_file);
  if (!scene) {
    std::cerr << "rhot-eval: " << scene.error().to_string() << "\n";
    return 1;
  }
  rhot::RendererSettings render;
  render.eye_width_px = scene->settings.headset.eye_width_px;
  render.eye_height_px = scene->settings.headset.eye_height_px;
  render.device = device;
  render.shading = shading;
  render.gpu_timings = options.gpu_timings;
  if (!eye.empty()) {
    char x = 0, rest = 0;
    if (std::sscanf(eye.c_str(), "%d%c%d%c", &render.eye_width_px, &x, &render.eye_height_px, &rest) != 3 || (x != 'x' && x != 'X') ||
        render.eye_width_px < 16 || render.eye_height_px < 16 || render.eye_width_px > 8192 || render.eye_height_px > 8192) {
      std::cerr << "rhot-eval: --eye: expected WIDTHxHEIGHT, each 16 to 8192 pixels, such as 1080x1200, got \"" << eye << "\"\n";
      return 1;
    }
  }
  std::unique_ptr<rhot::XrHeadset> headset;  // outlives the renderer
  if (options.xr) {
    auto opened = rhot::XrHeadset::create({"rhot-eval", false});
    if (!opened) {
      std::cerr << "rhot-eval: --xr: " << opened.error() << "\n";
      return 1;
    }
    headset = std::move(*opened);
  }
  auto renderer = rhot::Renderer::create(render, nullptr, headset.get());
  if (!renderer) {
    std::cerr << "rhot-eval: cannot start the renderer: " << renderer.error() << "\n";
    return 1;
  }
  const auto world = world_settings(world_flags);
  if (!world) {
    std::cerr << "rhot-eval: " << world.error() << "\n";
    return 1;
  }
  rhot::DemoSettings settings;
  settings.asset_dir = RHOT_ASSET_DIR;
  settings.world = *world;
  settings.sigma_px = world->sigma_px;
  settings.predict = options.prediction == "on";
  settings.threads = options.threads;
  auto demo = rhot::Demo::create(*scene, renderer->get(), settings);
  if (!demo) {
    std::cerr << "rhot-eval: " << demo.error() << "\n";
    return 1;
  }
  rhot::Systems systems;
  (*demo)->runtime().add_systems(systems, "");
  if (const auto built = systems.build(); !built) {
    std::cerr << "rhot-eval: " << built.error() << "\n";
    return 1;
  }
  rhot::FrameLoopSettings loop;
  loop.rate_hz = scene->settings.headset.refresh_hz;
  loop.budget_ms = 1000.0 / loop.rate_hz;
  loop.real_time = options.real_time;
  rhot::FrameLoop frame_loop((*demo)->world(), systems, rhot::headset_loop_settings((*demo)->runtime(), loop));
  // One run, so that a paced loop keeps one vsync grid (or, with --xr, one session).
  rhot::run_on_headset((*demo)->runtime(), frame_loop, static_cast<std::uint64_t>(frames), [&] {
    const std::uint64_t done = frame_loop.frame_index();
    if (done > 0 && done % 90 == 0) std::cerr << "rhot-eval: frame " << done << " of " << frames << "\n";
    return false;
  });
  nlohmann::json j = frame_loop.stats().to_json();
  // Latency (engine/runtime/Latency.h) and the drawn hands against the truth (engine/sim/Demo.h).
  const rhot::Runtime& runtime = (*demo)->runtime();
  const rhot::LatencyStats& latency = runtime.latency();
  j["latency"] = latency.to_json();
  j["tracking_latency_p99_ms"] = latency.tracking().p99_ms;
  j["motion_to_photon_p50_ms"] = latency.motion_to_photon().p50_ms;
  j["motion_to_photon_p99_ms"] = latency.motion_to_photon().p99_ms;
  const rhot::PredictionErrors& errors = (*demo)->prediction_errors();
  j["prediction"] = options.prediction;
  j["prediction_error_ratio"] = errors.ratio();
  j["prediction_errors"] = prediction_errors_json(errors);
  if (const auto gpu = runtime.gpu_eye_ms()) {
    for (std::size_t e = 0; e < 2; ++e) {
      j["gpu_eye_ms"][e == 0 ? "left" : "right"] = {{"p50", (*gpu)[e].p50_ms}, {"p99", (*gpu)[e].p99_ms}, {"max", (*gpu)[e].max_ms}};
    }
  }
  j["real_time"] = options.real_time;
  if (headset) {
    if (headset->frames_submitted() == 0) {
      std::cerr << "rhot-eval: --xr: no frame reached the headset\n";
      return 1;
    }
    j["xr"] = {{"runtime", headset->info().runtime},       {"system", headset->info().system},
               {"refresh_hz", headset->info().refresh_hz}, {"frames_shown", headset->frames_submitted()},
               {"frames_late", headset->frames_late()},    {"frames_late_own", headset->frames_late_own()},
               {"session_end", headset->exit_reason()}};
  }
  j["scene"] = scene_file;
  j["world"] = world_json(*world, world_flags.world);
  j["threads"] = threads_or_all(options.threads);
  j["eye_px"] = {(*renderer)->eye_width_px(), (*renderer)->eye_height_px()};
  j["device"] = (*renderer)->info().device_name;
  j["cpu_device"] = (*renderer)->info().cpu_device;
  j["stereo"] = (*renderer)->info().mode == rhot::StereoMode::kMultiview ? "multiview" : "two-pass";
  j["shading"] = rhot::to_string((*renderer)->info().shading);
  std::cout << j.dump(2) << "\n";
  return 0;
}

}  // namespace rhot::eval
