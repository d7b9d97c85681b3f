// rhot-demo: the VR demo. Loads a scene, runs one frame after another at a fixed 90 Hz step:
// simulated (or real: --source video:...) cameras -> tracking (markers, marker stars, hands) -> physics (hand colliders,
// grasping) -> both eyes rendered to a window or PNG files; reports frame statistics per stage.

#include <atomic>
#include <charconv>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

// GCC 12 at -O2 sees a "potential null pointer dereference" inside CLI11's option parsing
// (libstdc++'s string move); the pragma covers only CLI11's lines.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wnull-dereference"
#include <CLI/CLI.hpp>
#pragma GCC diagnostic pop
#include <nlohmann/json.hpp>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include "base/Jobs.h"
#include "engine/app/FrameLoop.h"
#include "engine/core/Transform.h"
#include "engine/core/World.h"
#include "engine/runtime/HeadsetLoop.h"
#include "engine/runtime/Overlay.h"
#include "engine/render/PngWriter.h"
#include "engine/render/Renderer.h"
#include "engine/render/SceneRenderer.h"
#include "engine/render/Window.h"
#include "engine/render/XrHeadset.h"
#include "engine/math/EigenGlm.h"
#include "tracking/calib/HeadsetRegistration.h"
#include "engine/scene/SceneLoader.h"
#include "engine/sim/Demo.h"
#include "tracking/sim/Realism.h"
#include "tracking/net/NodeSource.h"
#include "tracking/source/VideoSource.h"
#include "tools/common/CliExit.h"
#include "tools/common/NodeKeys.h"
#include "tools/common/NumberChecks.h"

#ifndef RHOT_ASSET_DIR
#error "RHOT_ASSET_DIR must name the assets folder"
#endif

namespace {

// Debug builds run with the Vulkan validation layer unless told otherwise.
#ifdef NDEBUG
constexpr bool kDebugBuild = false;
#else
constexpr bool kDebugBuild = true;
#endif

std::atomic<bool> g_interrupted{false};

void on_signal(int) { g_interrupted.store(true); }

// "1080x1200" -> {1080, 1200}
bool parse_size(const std::string& text, int& w, int& h) {
  char x = 0;
  char rest = 0;
  return std::sscanf(text.c_str(), "%d%c%d%c", &w, &x, &h, &rest) == 3 && (x == 'x' || x == 'X') && w > 0 && h > 0;
}

// The most frames --frames may ask for: 100 million, 13 days at 90 Hz. CLI11 alone would read "-1"
// as the largest 64-bit number and saturate 99999999999999999999999 to it: a run that never ends.
constexpr std::uint64_t kMaxFrames = 100'000'000;

// --frames: a whole number from 0 to kMaxFrames, checked on the text before CLI11 converts it.
CLI::Validator frame_count_check() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        std::uint64_t frames = 0;
        const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), frames);
        if (ec != std::errc() || end != text.data() + text.size() || frames > kMaxFrames) {
          return "expected a whole number of frames from 0 to " + std::to_string(kMaxFrames) + " (0: until closed), got " + text;
        }
        return {};
      },
      "0.." + std::to_string(kMaxFrames));
}

// Everything the command line says.
struct Options {
  std::string scene_path = std::string(RHOT_ASSET_DIR) + "/scenes/default.json";
  bool headless = false;
  std::uint64_t frames = 0;
  std::string stats_path;
  rhot::FrameLoopSettings loop;
  std::string log_level = "info";
  std::string capture_dir;
  std::string capture_layout = "eyes";
  std::string eye_size;
  rhot::RendererSettings render;
  std::string stereo = "auto";
  std::string shading = "auto";
  std::string world = "ideal";
  std::optional<double> sigma;
  std::optional<int> strays;
  std::optional<double> calib_error_px;
  std::string source = "sim";
  std::string markers = "infrared";
  rhot::DemoSettings demo;
  std::vector<std::string> debug_views;
  std::string window_capture;
  std::string prediction = "on";
  bool no_overlay = false;
  bool xr = false;           // on a headset through OpenXR
  bool mirror = false;       // with xr: the eyes in a desktop window too
  std::string registration;  // the rig registered to the headset (rhot-calib headset)
  bool no_publish = false;
  rhot::NodeKeyFlags node_keys;
};

void add_options(CLI::App& cli, Options& o) {
  cli.add_option("--scene", o.scene_path, "Scene file (JSON, see docs/scene-format.md)")->capture_default_str();
  cli.add_flag("--headless", o.headless, "Run without a window (also chosen when there is no display)");
  cli.add_option("--frames", o.frames, "Stop after N frames, 0 to 100000000 (0: until closed; headless default 900, 10 s at 90 Hz)")
      ->check(frame_count_check());
  cli.add_option("--stats", o.stats_path, "Write frame statistics (p50, p99, max per stage and frame) as JSON");
  cli.add_option("--rate-hz", o.loop.rate_hz, "Fixed simulation rate")->capture_default_str()->check(CLI::Range(1.0, 10000.0));
  cli.add_option("--budget-ms", o.loop.budget_ms, "Frame budget; slower frames count as misses")
      ->capture_default_str()
      ->check(rhot::number_check(rhot::NumberBound::kPositive));
  cli.add_option("--log-level", o.log_level, "trace, debug, info, warn, error or off")
      ->capture_default_str()
      ->check(CLI::IsMember({"trace", "debug", "info", "warn", "error", "off"}));
  o.render.validation = kDebugBuild;
  cli.add_option("--capture", o.capture_dir, "Write every frame as PNG into this folder (created if missing)");
  cli.add_option("--capture-layout", o.capture_layout, "eyes: one PNG per eye; side-by-side: both eyes in one PNG")
      ->capture_default_str()
      ->check(CLI::IsMember({"eyes", "side-by-side"}));
  cli.add_option("--eye", o.eye_size, "Pixels per eye, WxH (default: the scene's headset, 1080x1200)");
  cli.add_option("--device", o.render.device, "Vulkan device: auto, gpu, cpu, an index or part of its name (or set RHOT_VK_DEVICE)")
      ->capture_default_str();
  cli.add_option("--stereo", o.stereo, "auto (multiview where the driver passes a self-test), multiview or two-pass")
      ->capture_default_str()
      ->check(CLI::IsMember({"auto", "multiview", "two-pass"}));
  cli.add_option("--shading", o.shading, "light per pixel, per vertex, or auto (per vertex on a CPU driver, where it halves the frame)")
      ->capture_default_str()
      ->check(CLI::IsMember({"auto", "pixel", "vertex"}));
  cli.add_option("--prediction", o.prediction, "draw the hands where they will be when the frame is shown (on) or where tracked (off)")
      ->capture_default_str()
      ->check(CLI::IsMember({"on", "off"}));
  cli.add_flag("--gpu-timings", o.render.gpu_timings, "GPU timestamps around each eye's pass (logged at the end)");
  cli.add_flag("--validation,!--no-validation", o.render.validation,
               "Vulkan validation layer (default: on in debug builds; or set RHOT_VK_VALIDATION=1)");
  o.demo.asset_dir = RHOT_ASSET_DIR;
  cli.add_option("--source", o.source,
                 "sim (the built-in simulated camera rig), replay:FILE (a recording made with --record), or video:DEV[,DEV...] "
                 "(real cameras, one per camera of --rig in rig order: a capture device index such as 0, a video file, or an image "
                 "sequence such as cams/cam0_%04d.png; docs/demo.md), or nodes:NAME@ENDPOINT[,NAME@ENDPOINT...] (camera nodes, "
                 "rhot-node, each publishing at ENDPOINT such as tcp://127.0.0.1:5601, NAME.key its certificate in --keys DIR/trusted/; "
                 "with --insecure, nodes:ENDPOINT[,...]; docs/camera-nodes.md)")
      ->capture_default_str();
  rhot::add_node_key_flags(cli, o.node_keys);
  cli.add_option("--markers", o.markers,
                 "infrared (bright blobs, the low-cost hand layouts) or colour (seed 002's coloured markers: the colour hand layouts; "
                 "with --source sim, colour cameras drawn by the renderer on assets/rigs/stereo-640.yaml unless --rig; "
                 "docs/colour-markers.md)")
      ->capture_default_str()
      ->check(CLI::IsMember({"infrared", "colour"}));
  cli.add_option("--colours", o.demo.colours,
                 "With --markers colour: the colour model (rhot-calib colours writes one; default: rhot's six)")
      ->check(CLI::ExistingFile);
  cli.add_option("--white-balance-k", o.demo.colour_cameras.kelvin,
                 "With --markers colour and --source sim: the simulated light's colour temperature (cameras balanced for 6500 K)")
      ->capture_default_str()
      ->check(CLI::Range(1500.0, 15000.0));
  cli.add_option("--blob-threshold", o.demo.detector.threshold,
                 "With --source video: grey level above which pixels are marker (-1: automatic, background + 5 sigma, at least 40)")
      ->capture_default_str()
      ->check(CLI::Range(-1, 254));
  cli.add_option("--speed", o.demo.speed, "Replay speed (with --source replay:FILE)")
      ->capture_default_str()
      ->check(CLI::Range(0.01, 100.0));
  cli.add_option("--record", o.demo.record,
                 "Record every frame's hands and tracked objects to FILE (JSON Lines, docs/recording-format.md)");
  cli.add_option("--stream", o.demo.stream,
                 "Send every frame's hands and tracked objects as OSC to osc://HOST:PORT (rhot's addresses) or osc://HOST:PORT,vmc "
                 "(the VMC protocol's hand bones and trackers; docs/streaming.md); default: nowhere");
  cli.add_option("--rig", o.demo.rig_file, "Camera rig (OpenCV YAML; default: the scene's, else assets/rigs/seated-4.yaml)")
      ->check(CLI::ExistingFile);
  cli.add_option("--world", o.world,
                 "The simulated world: ideal (0.3 px, nothing else) or realistic (0.5 px, dropout, strays, 6 mm markers that merge, "
                 "unsynchronised cameras, a 0.3 px calibration error, users' own hands; docs/tracking.md)")
      ->capture_default_str()
      ->check(CLI::IsMember({"ideal", "realistic"}));
  cli.add_option("--sigma", o.sigma, "Simulated pixel noise, standard deviation (default: the world's)")->check(CLI::Range(0.0, 50.0));
  cli.add_option("--strays", o.strays, "Simulated false blobs per camera per frame (default: the world's)")->check(CLI::Range(0, 1000));
  cli.add_option("--calib-error-px", o.calib_error_px, "The tracker's rig off the simulated one by about this reprojection error")
      ->check(CLI::Range(0.0, 20.0));
  cli.add_option("--seed", o.demo.seed, "Simulation seed")->capture_default_str();
  cli.add_flag("--filter", o.demo.filter_hands, "1-euro filter the tracked hands (steadier at rest, some lag)");
  cli.add_flag("--filter-frame,!--no-filter-frame", o.demo.filter_hand_frames,
               "1-euro filter each tracked hand's frame alone (on by default: steadier fingers, hidden ones too)");
  cli.add_option("--threads", o.demo.threads, "Threads the tracker matches on (0: every core there is); the results do not depend on it")
      ->capture_default_str()
      ->check(CLI::Range(0, rhot::kMaxThreads));
  cli.add_option("--debug-views", o.debug_views, "Debug views on from the start: markers, rays, frusta, colliders (comma-separated)")
      ->delimiter(',')
      ->check(CLI::IsMember({"markers", "rays", "frusta", "colliders"}));
  cli.add_flag("--points", o.demo.debug.markers, "Draw the triangulated marker points (as --debug-views markers)");
  cli.add_option("--window-capture", o.window_capture,
                 "With a window and --frames: write what it shows on the last frame (both eyes and the overlay) as PNG");
  cli.add_flag("--no-overlay", o.no_overlay, "No Dear ImGui overlay in the window");
  cli.add_flag("--xr", o.xr,
               "Show on a headset through the active OpenXR runtime (or the one XR_RUNTIME_JSON names; docs/openxr.md). "
               "--frames N: end the session after N frames shown");
  cli.add_flag("--mirror", o.mirror, "With --xr: also show both eyes in a desktop window");
  cli.add_option("--registration", o.registration,
                 "The rig registered to the headset's space (rhot-calib headset --out FILE), for --xr and the published hands; default: "
                 "the two taken as one");
  cli.add_flag("--no-publish", o.no_publish,
               "Do not publish the hands for other processes (rhot's OpenXR layer gives them to OpenXR applications; docs/openxr.md)");
}

// --stats FILE is written after the run, so whether it can be written is checked before: a long run
// must not end in "cannot write". The file is opened for appending (one that exists is left as it
// is) and, where the check made it, removed again. False after logging why it cannot be written.
bool stats_file_writable(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (fs::is_directory(path, ec)) {
    spdlog::error("--stats: cannot write {}: it is a folder", path);
    return false;
  }
  const fs::path folder = fs::path(path).parent_path();
  if (!folder.empty() && !fs::is_directory(folder, ec)) {
    spdlog::error("--stats: cannot write {}: the folder {} does not exist", path, folder.string());
    return false;
  }
  const bool existed = fs::exists(path, ec);
  if (!std::ofstream(path, std::ios::app)) {
    spdlog::error("--stats: cannot write {}: it cannot be opened for writing", path);
    return false;
  }
  if (!existed) fs::remove(path, ec);
  return true;
}

// What the options mean beyond their own checks: the source, the debug views, the eye size, where
// --stats goes. False after logging what is wrong.
bool resolve_options(Options& o) {
  for (const std::string& v : o.debug_views) {
    if (v == "markers") o.demo.debug.markers = true;
    if (v == "rays") o.demo.debug.rays = true;
    if (v == "frusta") o.demo.debug.frusta = true;
    if (v == "colliders") o.demo.debug.colliders = true;
  }
  spdlog::set_level(spdlog::level::from_str(o.log_level));
  o.demo.colour_markers = o.markers == "colour";
  if (!o.demo.colours.empty() && !o.demo.colour_markers) {
    spdlog::error("--colours: a colour model needs --markers colour");
    return false;
  }
  if (o.source.rfind("replay:", 0) == 0 && o.source.size() > 7) {
    o.demo.replay = o.source.substr(7);
  } else if (o.source.rfind("video:", 0) == 0) {
    auto devices = rhot::parse_video_devices(o.source.substr(6));
    if (!devices) {
      spdlog::error("--source: {}", devices.error());
      return false;
    }
    o.demo.video_devices = std::move(*devices);
  } else if (o.source.rfind("nodes:", 0) == 0) {
    auto endpoints = rhot::parse_node_endpoints(o.source.substr(6));
    if (!endpoints) {
      spdlog::error("--source: {}", endpoints.error());
      return false;
    }
    o.demo.node_endpoints = std::move(*endpoints);
  } else if (o.source != "sim") {
    spdlog::error("--source: expected sim, replay:FILE, video:DEV[,DEV...] or nodes:NAME@ENDPOINT[,...], got \"{}\"", o.source);
    return false;
  }
  auto security = rhot::node_security_from(o.node_keys, !o.demo.node_endpoints.empty());
  if (!security) {
    spdlog::error("{}", security.error());
    return false;
  }
  o.demo.node_security = std::move(*security);
  auto world = rhot::world_named(o.world);
  if (!world) {
    spdlog::error("{}", world.error());
    return false;
  }
  if (o.sigma) world->sigma_px = *o.sigma;
  if (o.strays) world->strays = *o.strays;
  if (o.calib_error_px) world->calib_error_px = *o.calib_error_px;
  o.demo.sigma_px = world->sigma_px;
  o.demo.world = *world;
  o.demo.predict = o.prediction == "on";
  if (auto checked = o.demo.check(); !checked) {
    spdlog::error("{}", checked.error());
    return false;
  }
  if (auto checked = o.loop.check(); !checked) {
    spdlog::error("{}", checked.error());
    return false;
  }
  if (!o.eye_size.empty() && !parse_size(o.eye_size, o.render.eye_width_px, o.render.eye_height_px)) {
    spdlog::error("--eye: expected WIDTHxHEIGHT in pixels, such as 1080x1200, got \"{}\"", o.eye_size);
    return false;
  }
  if (o.mirror && !o.xr) {
    spdlog::error("--mirror: needs --xr (without a headset the window shows the eyes anyway)");
    return false;
  }
  o.demo.publish_hands = !o.no_publish;
  if (o.xr) {
    // The headset is the display; a window only as its mirror. The runtime's recommended eye size
    // is used, and the session runs until the runtime ends it, --frames are shown or it is stopped.
    if (!o.eye_size.empty()) spdlog::warn("--eye ignored with --xr: the eyes take the headset runtime's recommended size");
    o.headless = !o.mirror;
  }
  if (!o.headless && !rhot::Window::display_available()) {
    spdlog::info("no display found (DISPLAY and WAYLAND_DISPLAY are unset); running headless");
    o.headless = true;
  }
  if (o.headless && o.frames == 0 && !o.xr) o.frames = 900;
  o.render.stereo = o.stereo == "multiview"  ? rhot::StereoMode::kMultiview
                    : o.stereo == "two-pass" ? rhot::StereoMode::kTwoPass
                                             : rhot::StereoMode::kAuto;
  o.render.shading = *rhot::shading_from_string(o.shading);  // checked by the option
  if (!o.capture_dir.empty()) {
    std::error_code ec;
    std::filesystem::create_directories(o.capture_dir, ec);
    if (ec) {
      spdlog::error("--capture: cannot create folder {}: {}", o.capture_dir, ec.message());
      return false;
    }
  }
  return o.stats_path.empty() || stats_file_writable(o.stats_path);
}

// Both eyes side by side, scaled to fit a desktop; headless (null) when no window opens.
std::unique_ptr<rhot::Window> open_window(Options& o) {
  if (o.headless) return nullptr;
  const double scale = std::min(1.0, 1600.0 / (2.0 * o.render.eye_width_px));
  auto created =
      rhot::Window::create("rhot", static_cast<int>(2.0 * o.render.eye_width_px * scale), static_cast<int>(o.render.eye_height_px * scale));
  if (created) return std::move(*created);
  spdlog::warn("cannot open a window ({}); running headless", created.error());
  o.headless = true;
  if (o.frames == 0) o.frames = 900;
  return nullptr;
}

// The PNG files --capture writes for one frame, queued for the writer's threads (encoding a
// full-size frame takes longer than a frame).
void capture_frame(const Options& o, rhot::Renderer& renderer, rhot::PngWriter& writer, std::uint64_t frame_index) {
  char stem[32];
  std::snprintf(stem, sizeof(stem), "frame_%06llu", static_cast<unsigned long long>(frame_index));
  auto eyes = renderer.read_eyes();
  const std::filesystem::path dir(o.capture_dir);
  if (o.capture_layout == "side-by-side") {
    writer.write(rhot::side_by_side(eyes[0], eyes[1]), dir / (std::string(stem) + ".png"));
    return;
  }
  writer.write(std::move(eyes[0]), dir / (std::string(stem) + "_left.png"));
  writer.write(std::move(eyes[1]), dir / (std::string(stem) + "_right.png"));
}

// --window-capture and --stats, after the run. False after logging what failed.
bool write_outputs(const Options& o, const rhot::Window* window, rhot::Renderer& renderer, const rhot::FrameLoop& frame_loop,
                   const rhot::LatencyStats& latency) {
  if (!o.window_capture.empty()) {
    if (!window) {
      spdlog::error("--window-capture: there is no window (headless)");
      return false;
    }
    const rhot::Image& shown = renderer.window_image();
    if (shown.width == 0) {
      spdlog::error("--window-capture: no frame was captured (it needs --frames N, and a window that is not minimised)");
      return false;
    }
    if (const auto written = rhot::write_png(shown, o.window_capture); !written) {
      spdlog::error("--window-capture: {}", written.error());
      return false;
    }
    spdlog::info("window written to {}", o.window_capture);
  }
  if (!o.stats_path.empty()) {
    nlohmann::json j = frame_loop.stats().to_json();
    j["scene"] = o.scene_path;
    j["rate_hz"] = o.loop.rate_hz;
    j["latency"] = latency.to_json();
    if (const rhot::XrHeadset* xr = renderer.headset()) {
      j["xr"] = {{"runtime", xr->info().runtime},
                 {"system", xr->info().system},
                 {"refresh_hz", xr->info().refresh_hz},
                 {"frames_shown", xr->frames_submitted()},
                 {"frames_late", xr->frames_late()},
                 {"frames_late_own", xr->frames_late_own()},
                 {"validation_enabled", xr->info().validation_enabled},
                 {"validation_messages", xr->validation_messages()},
                 {"vulkan_validation_enabled", renderer.info().validation_enabled},
                 {"vulkan_validation_messages", renderer.validation_messages()},
                 {"session_end", xr->exit_reason()}};
    }
    std::ofstream out(o.stats_path);
    out << j.dump(2) << '\n';
    out.close();
    if (!out) {
      spdlog::error("cannot write statistics to {}", o.stats_path);
      return false;
    }
    spdlog::info("statistics written to {}", o.stats_path);
  }
  return true;
}

// The window's overlay (frame times, stages, tracking state), drawn by the runtime every frame;
// none headless or with --no-overlay.
std::unique_ptr<rhot::Overlay> make_overlay(const Options& o, const rhot::Window* window, rhot::Renderer& renderer, rhot::Runtime& runtime,
                                            const rhot::FrameLoop& frame_loop) {
  if (!window || o.no_overlay) return nullptr;
  if (const auto enabled = renderer.enable_overlay(); !enabled) {
    spdlog::warn("no overlay: {}", enabled.error());
    return nullptr;
  }
  auto overlay = std::make_unique<rhot::Overlay>(
      runtime, frame_loop.stats(),
      rhot::OverlayInfo{o.scene_path, o.source, renderer.info().device_name + ", lit per " + rhot::to_string(renderer.info().shading),
                        o.render.eye_width_px, o.render.eye_height_px});
  runtime.set_overlay([drawn = overlay.get()] { drawn->build(); });
  return overlay;
}

// The run's figures, after it: frame times, latency, the stream's counts.
void log_run(const Options& o, std::uint64_t ran, const rhot::FrameLoop& frame_loop, rhot::Runtime& runtime) {
  const rhot::FrameStats& stats = frame_loop.stats();
  const rhot::TimingSummary whole = stats.frame_summary();
  spdlog::info(
      "{} frames ({:.1f} s simulated): frame p50 {:.3f} ms, p99 {:.3f} ms, max {:.3f} ms; {} over the "
      "{:.1f} ms budget",
      ran, frame_loop.time_s(), whole.p50_ms, whole.p99_ms, whole.max_ms, stats.frames_over_budget(), stats.budget_ms());
  const rhot::LatencyStats& latency = runtime.latency();
  if (latency.frames() > 0) {
    spdlog::info("latency p50 / p99: tracking {:.2f} / {:.2f} ms, render {:.2f} / {:.2f} ms, motion-to-photon {:.2f} / {:.2f} ms",
                 latency.tracking().p50_ms, latency.tracking().p99_ms, latency.render().p50_ms, latency.render().p99_ms,
                 latency.motion_to_photon().p50_ms, latency.motion_to_photon().p99_ms);
  }
  if (const auto streamed = runtime.stream_stats()) {
    spdlog::info("stream {}: {} frames, {} sent, {} skipped (the sender was busy), {} failed sends", o.demo.stream, streamed->given,
                 streamed->sent, streamed->skipped, streamed->errors);
  }
}

// The headset's figures after the run; false where the session failed (it never showed a frame,
// or the runtime lost it).
bool report_headset(const rhot::XrHeadset& headset) {
  spdlog::info(
      "OpenXR: {} frames shown, {} submitted after their display time ({} through rhot's own work); {} OpenXR validation "
      "message(s); {}",
      headset.frames_submitted(), headset.frames_late(), headset.frames_late_own(), headset.validation_messages(),
      headset.exit_reason().empty() ? "the session did not end" : headset.exit_reason());
  if (headset.frames_submitted() == 0) {
    spdlog::error("--xr: no frame reached the headset");
    return false;
  }
  return !headset.lost();
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App cli{
      "rhot-demo: tracked hands and objects in VR, drawn for both eyes of a headset.\n"
      "With no arguments it runs the default scene; with no display it runs headless."};
  Options o;
  add_options(cli, o);
  // Everything on stderr, progress and figures as well as errors, as rhot's other tools do.
  spdlog::set_default_logger(spdlog::stderr_color_mt("rhot-demo"));
  try {
    cli.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return rhot::cli_exit_status(cli, e);
  }
  if (!resolve_options(o)) return EXIT_FAILURE;

  const auto scene = rhot::load_scene_file(o.scene_path);
  if (!scene) {
    spdlog::error("cannot load scene: {}", scene.error().to_string());
    return EXIT_FAILURE;
  }
  if (o.eye_size.empty()) {
    o.render.eye_width_px = scene->settings.headset.eye_width_px;
    o.render.eye_height_px = scene->settings.headset.eye_height_px;
  }
  std::unique_ptr<rhot::XrHeadset> headset;  // outlives the renderer
  if (o.xr) {
    auto opened = rhot::XrHeadset::create({"rhot-demo", o.render.validation});
    if (!opened) {
      spdlog::error("--xr: {}", opened.error());
      return EXIT_FAILURE;
    }
    headset = std::move(*opened);
  }
  if (!o.registration.empty()) {
    const auto registration = rhot::read_headset_registration(o.registration);
    if (!registration) {
      spdlog::error("--registration: {}", registration.error());
      return EXIT_FAILURE;
    }
    if (headset) {
      if (const auto set = headset->set_world_from_stage(rhot::to_glm(registration->world_from_stage)); !set) {
        spdlog::error("--registration: {}: {}", o.registration, set.error());
        return EXIT_FAILURE;
      }
    }
    o.demo.world_from_stage = registration->world_from_stage;
    spdlog::info("the rig registered to the headset by {} ({} samples, {:.2f} mm RMS)", o.registration, registration->samples,
                 registration->rms_mm);
  }
  std::unique_ptr<rhot::Window> window = open_window(o);
  auto renderer = rhot::Renderer::create(o.render, window.get(), headset.get());
  if (!renderer) {
    spdlog::error("cannot start the renderer: {}", renderer.error());
    return EXIT_FAILURE;
  }
  auto demo = rhot::Demo::create(*scene, renderer->get(), o.demo);
  if (!demo) {
    spdlog::error("cannot start the demo: {}", demo.error());
    return EXIT_FAILURE;
  }
  rhot::Runtime& runtime = (*demo)->runtime();
  const rhot::CameraRig* rig = runtime.tracking().rig();
  spdlog::info("scene {}: tracking {} cameras, {} star-tracked objects", o.scene_path, rig ? rig->cameras.size() : 0,
               runtime.objects().objects.size());

  bool capture_failed = false;
  rhot::Systems systems;
  systems.add({"window-events", {}, {}, [&](rhot::World&, const rhot::FrameContext& f) {
                 if (!window) return;
                 window->poll_events();
                 if (!o.window_capture.empty() && o.frames > 0 && f.frame_index + 1 == o.frames) (void)(*renderer)->capture_window();
               }});
  runtime.add_systems(systems, "window-events");
  std::optional<rhot::PngWriter> png_writer;
  if (!o.capture_dir.empty()) png_writer.emplace();
  systems.add({"capture", {"render"}, {}, [&](rhot::World&, const rhot::FrameContext& f) {
                 if (!png_writer || capture_failed) return;
                 if (const auto failed = png_writer->error()) {
                   spdlog::error("capture stopped: {}", *failed);
                   capture_failed = true;
                   return;
                 }
                 capture_frame(o, **renderer, *png_writer, f.frame_index);
               }});
  if (const auto built = systems.build(); !built) {
    spdlog::error("cannot order systems: {}", built.error());
    return EXIT_FAILURE;
  }

  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  // A headset's runtime paces the frames (xrWaitFrame; HeadsetLoop.h); the simulation keeps its fixed step.
  o.loop.real_time = !o.headless;
  rhot::FrameLoop frame_loop(runtime.world(), systems, rhot::headset_loop_settings(runtime, o.loop));
  const std::unique_ptr<rhot::Overlay> overlay = make_overlay(o, window.get(), **renderer, runtime, frame_loop);
  const auto stop_asked = [&] { return g_interrupted.load() || (window && window->should_close()) || runtime.tracking().ended(); };
  const std::uint64_t ran = rhot::run_on_headset(runtime, frame_loop, o.frames, stop_asked);
  for (const std::string& line : runtime.tracking().summary()) spdlog::info("{}", line);
  if (png_writer) {
    if (const auto failed = png_writer->finish(); failed && !capture_failed) {
      spdlog::error("capture stopped: {}", *failed);
      capture_failed = true;
    }
    spdlog::info("captured {} PNG file(s) into {}", png_writer->written(), o.capture_dir);
  }

  log_run(o, ran, frame_loop, runtime);
  if (!write_outputs(o, window.get(), **renderer, frame_loop, runtime.latency())) return EXIT_FAILURE;
  const std::uint64_t validation = (*renderer)->validation_messages();
  if (validation > 0) spdlog::warn("{} Vulkan validation message(s)", validation);
  const bool headset_failed = headset && !report_headset(*headset);
  return capture_failed || headset_failed ? EXIT_FAILURE : EXIT_SUCCESS;
}
