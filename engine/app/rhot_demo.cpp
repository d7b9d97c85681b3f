// rhot-demo: the VR demo. Loads a scene, runs one frame after another at a fixed 90 Hz step:
// simulated (or real: --source video:...) cameras -> tracking (markers, marker stars, hands) -> physics (hand colliders,
// grasping) -> both eyes rendered to a window or PNG files; reports frame statistics per stage.

#include <atomic>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

// GCC 12 at -O2 sees a "potential null pointer dereference" inside CLI11's option parsing
// (libstdc++'s string move); the pragma covers only CLI11's lines.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wnull-dereference"
#include <CLI/CLI.hpp>
#pragma GCC diagnostic pop
#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include "engine/app/FrameLoop.h"
#include "engine/core/Transform.h"
#include "engine/core/World.h"
#include "engine/demo/DemoOverlay.h"
#include "engine/demo/DemoRuntime.h"
#include "engine/render/Renderer.h"
#include "engine/render/SceneRenderer.h"
#include "engine/render/Window.h"
#include "engine/scene/SceneLoader.h"

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

}  // namespace

int main(int argc, char** argv) {
  CLI::App cli{
      "rhot-demo: tracked hands and objects in VR, drawn for both eyes of a headset.\n"
      "With no arguments it runs the default scene; with no display it runs headless."};
  std::string scene_path = std::string(RHOT_ASSET_DIR) + "/scenes/default.json";
  bool headless = false;
  std::uint64_t frames = 0;
  std::string stats_path;
  rhot::FrameLoopSettings loop;
  std::string log_level = "info";
  cli.add_option("--scene", scene_path, "Scene file (JSON, see docs/scene-format.md)")->capture_default_str();
  cli.add_flag("--headless", headless, "Run without a window (also chosen when there is no display)");
  cli.add_option("--frames", frames, "Stop after N frames (0: until closed; headless default 900, 10 s at 90 Hz)");
  cli.add_option("--stats", stats_path, "Write frame statistics (p50, p99, max per stage and frame) as JSON");
  cli.add_option("--rate-hz", loop.rate_hz, "Fixed simulation rate")->capture_default_str()->check(CLI::Range(1.0, 10000.0));
  cli.add_option("--budget-ms", loop.budget_ms, "Frame budget; slower frames count as misses")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  cli.add_option("--log-level", log_level, "trace, debug, info, warn, error or off")
      ->capture_default_str()
      ->check(CLI::IsMember({"trace", "debug", "info", "warn", "error", "off"}));
  std::string capture_dir;
  std::string capture_layout = "eyes";
  std::string eye_size;
  rhot::RendererSettings render;
  render.validation = kDebugBuild;
  std::string stereo = "auto";
  cli.add_option("--capture", capture_dir, "Write every frame as PNG into this folder (created if missing)");
  cli.add_option("--capture-layout", capture_layout, "eyes: one PNG per eye; side-by-side: both eyes in one PNG")
      ->capture_default_str()
      ->check(CLI::IsMember({"eyes", "side-by-side"}));
  cli.add_option("--eye", eye_size, "Pixels per eye, WxH (default: the scene's headset, 1080x1200)");
  cli.add_option("--device", render.device, "Vulkan device: auto, gpu, cpu, an index or part of its name (or set RHOT_VK_DEVICE)")
      ->capture_default_str();
  cli.add_option("--stereo", stereo, "auto (multiview where the driver passes a self-test), multiview or two-pass")
      ->capture_default_str()
      ->check(CLI::IsMember({"auto", "multiview", "two-pass"}));
  std::string shading = "auto";
  cli.add_option("--shading", shading, "light per pixel, per vertex, or auto (per vertex on a CPU driver, where it halves the frame)")
      ->capture_default_str()
      ->check(CLI::IsMember({"auto", "pixel", "vertex"}));
  cli.add_flag("--validation,!--no-validation", render.validation,
               "Vulkan validation layer (default: on in debug builds; or set RHOT_VK_VALIDATION=1)");
  std::string source = "sim";
  rhot::DemoOptions demo;
  demo.pipeline.asset_dir = RHOT_ASSET_DIR;
  cli.add_option("--source", source,
                 "sim (the built-in simulated camera rig), replay:FILE (a recording made with --record), or video:DEV[,DEV...] "
                 "(real cameras, one per camera of --rig in rig order: a capture device index such as 0, a video file, or an image "
                 "sequence such as cams/cam0_%04d.png; docs/demo.md)")
      ->capture_default_str();
  cli.add_option("--blob-threshold", demo.pipeline.detector.threshold,
                 "With --source video: grey level above which pixels are marker (-1: automatic, background + 5 sigma, at least 40)")
      ->capture_default_str()
      ->check(CLI::Range(-1, 254));
  cli.add_option("--speed", demo.pipeline.speed, "Replay speed (with --source replay:FILE)")
      ->capture_default_str()
      ->check(CLI::Range(0.01, 100.0));
  cli.add_option("--record", demo.pipeline.record,
                 "Record every frame's hands and tracked objects to FILE (JSON Lines, docs/recording-format.md)");
  cli.add_option("--rig", demo.pipeline.rig_file, "Camera rig (OpenCV YAML; default: the scene's, else assets/rigs/seated-4.yaml)")
      ->check(CLI::ExistingFile);
  cli.add_option("--sigma", demo.pipeline.sigma_px, "Simulated pixel noise, standard deviation")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 50.0));
  cli.add_option("--seed", demo.pipeline.seed, "Simulation seed")->capture_default_str();
  cli.add_flag("--filter", demo.pipeline.filter_hands, "1-euro filter the tracked hands (steadier at rest, some lag)");
  std::vector<std::string> debug_views;
  cli.add_option("--debug-views", debug_views, "Debug views on from the start: markers, rays, frusta, colliders (comma-separated)")
      ->delimiter(',')
      ->check(CLI::IsMember({"markers", "rays", "frusta", "colliders"}));
  cli.add_flag("--points", demo.debug.markers, "Draw the triangulated marker points (as --debug-views markers)");
  std::string window_capture;
  cli.add_option("--window-capture", window_capture,
                 "With a window and --frames: write what it shows on the last frame (both eyes and the overlay) as PNG");
  bool no_overlay = false;
  cli.add_flag("--no-overlay", no_overlay, "No Dear ImGui overlay in the window");
  CLI11_PARSE(cli, argc, argv);
  for (const std::string& v : debug_views) {
    if (v == "markers") demo.debug.markers = true;
    if (v == "rays") demo.debug.rays = true;
    if (v == "frusta") demo.debug.frusta = true;
    if (v == "colliders") demo.debug.colliders = true;
  }
  spdlog::set_level(spdlog::level::from_str(log_level));
  if (source.rfind("replay:", 0) == 0 && source.size() > 7) {
    demo.pipeline.replay = source.substr(7);
  } else if (source.rfind("video:", 0) == 0) {
    auto devices = rhot::parse_video_devices(source.substr(6));
    if (!devices) {
      spdlog::error("--source: {}", devices.error());
      return EXIT_FAILURE;
    }
    demo.pipeline.video_devices = std::move(*devices);
  } else if (source != "sim") {
    spdlog::error("--source: expected sim, replay:FILE or video:DEV[,DEV...], got \"{}\"", source);
    return EXIT_FAILURE;
  }

  if (!eye_size.empty() && !parse_size(eye_size, render.eye_width_px, render.eye_height_px)) {
    spdlog::error("--eye: expected WIDTHxHEIGHT in pixels, such as 1080x1200, got \"{}\"", eye_size);
    return EXIT_FAILURE;
  }
  if (!headless && !rhot::Window::display_available()) {
    spdlog::info("no display found (DISPLAY and WAYLAND_DISPLAY are unset); running headless");
    headless = true;
  }
  if (headless && frames == 0) frames = 900;

  const auto scene = rhot::load_scene_file(scene_path);
  if (!scene) {
    spdlog::error("cannot load scene: {}", scene.error().to_string());
    return EXIT_FAILURE;
  }
  const rhot::HeadsetSettings& headset = scene->settings.headset;
  if (eye_size.empty()) {
    render.eye_width_px = headset.eye_width_px;
    render.eye_height_px = headset.eye_height_px;
  }
  render.stereo = stereo == "multiview"  ? rhot::StereoMode::kMultiview
                  : stereo == "two-pass" ? rhot::StereoMode::kTwoPass
                                         : rhot::StereoMode::kAuto;
  render.shading = *rhot::shading_from_string(shading);  // checked by the option
  if (!capture_dir.empty()) {
    std::error_code ec;
    std::filesystem::create_directories(capture_dir, ec);
    if (ec) {
      spdlog::error("--capture: cannot create folder {}: {}", capture_dir, ec.message());
      return EXIT_FAILURE;
    }
  }

  std::unique_ptr<rhot::Window> window;
  if (!headless) {
    // Both eyes side by side, scaled to fit a desktop.
    const double scale = std::min(1.0, 1600.0 / (2.0 * render.eye_width_px));
    auto created =
        rhot::Window::create("rhot", static_cast<int>(2.0 * render.eye_width_px * scale), static_cast<int>(render.eye_height_px * scale));
    if (created) {
      window = std::move(*created);
    } else {
      spdlog::warn("cannot open a window ({}); running headless", created.error());
      headless = true;
      if (frames == 0) frames = 900;
    }
  }
  auto renderer = rhot::Renderer::create(render, window.get());
  if (!renderer) {
    spdlog::error("cannot start the renderer: {}", renderer.error());
    return EXIT_FAILURE;
  }

  auto runtime = rhot::DemoRuntime::create(*scene, renderer->get(), demo);
  if (!runtime) {
    spdlog::error("cannot start the demo: {}", runtime.error());
    return EXIT_FAILURE;
  }
  rhot::World& world = (*runtime)->world();
  spdlog::info("scene {}: tracking {} cameras, {} star-tracked objects", scene_path, (*runtime)->pipeline().rig().cameras.size(),
               world.view<rhot::TrackedBy>().size_hint());
  bool capture_failed = false;

  rhot::Systems systems;
  systems.add({"window-events", {}, {}, [&](rhot::World&, const rhot::FrameContext& f) {
                 if (!window) return;
                 window->poll_events();
                 if (!window_capture.empty() && frames > 0 && f.frame_index + 1 == frames) (void)(*renderer)->capture_window();
               }});
  (*runtime)->add_systems(systems, "window-events");
  systems.add({"capture", {"render"}, {}, [&](rhot::World&, const rhot::FrameContext& f) {
                 if (capture_dir.empty() || capture_failed) return;
                 char stem[32];
                 std::snprintf(stem, sizeof(stem), "frame_%06llu", static_cast<unsigned long long>(f.frame_index));
                 const auto eyes = (*renderer)->read_eyes();
                 const std::filesystem::path dir(capture_dir);
                 std::expected<void, std::string> written;
                 if (capture_layout == "side-by-side") {
                   written = rhot::write_png(rhot::side_by_side(eyes[0], eyes[1]), dir / (std::string(stem) + ".png"));
                 } else {
                   written = rhot::write_png(eyes[0], dir / (std::string(stem) + "_left.png"));
                   if (written) written = rhot::write_png(eyes[1], dir / (std::string(stem) + "_right.png"));
                 }
                 if (!written) {
                   spdlog::error("capture stopped: {}", written.error());
                   capture_failed = true;
                 }
               }});
  if (const auto built = systems.build(); !built) {
    spdlog::error("cannot order systems: {}", built.error());
    return EXIT_FAILURE;
  }

  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  loop.real_time = !headless;
  rhot::FrameLoop frame_loop(world, systems, loop);
  std::unique_ptr<rhot::DemoOverlay> overlay;
  if (window && !no_overlay) {
    if (const auto enabled = (*renderer)->enable_overlay(); enabled) {
      overlay = std::make_unique<rhot::DemoOverlay>(
          **runtime, frame_loop.stats(),
          rhot::OverlayInfo{scene_path, source,
                            (*renderer)->info().device_name + ", lit per " + rhot::to_string((*renderer)->info().shading),
                            render.eye_width_px, render.eye_height_px});
      (*runtime)->set_overlay([&overlay] { overlay->build(); });
    } else {
      spdlog::warn("no overlay: {}", enabled.error());
    }
  }
  rhot::Pipeline& pipeline = (*runtime)->pipeline();
  const std::uint64_t ran =
      frame_loop.run(frames, [&] { return !g_interrupted.load() && !(window && window->should_close()) && !pipeline.source_ended(); });
  if (const rhot::VideoSource* video = pipeline.video()) {
    for (std::size_t c = 0; c < video->stats().size(); ++c) {
      const rhot::VideoCameraStats& s = video->stats()[c];
      spdlog::info("video camera {} ({}): {} frames, {} bad images, {} failed reads", c, video->devices()[c], s.frames, s.bad_images,
                   s.failed_reads);
    }
  }

  if (!window_capture.empty()) {
    if (!window) {
      spdlog::error("--window-capture: there is no window (headless)");
      return EXIT_FAILURE;
    }
    const rhot::Image& shown = (*renderer)->window_image();
    if (shown.width == 0) {
      spdlog::error("--window-capture: no frame was captured (it needs --frames N, and a window that is not minimised)");
      return EXIT_FAILURE;
    }
    if (const auto written = rhot::write_png(shown, window_capture); !written) {
      spdlog::error("--window-capture: {}", written.error());
      return EXIT_FAILURE;
    }
    spdlog::info("window written to {}", window_capture);
  }

  const rhot::FrameStats& stats = frame_loop.stats();
  const rhot::TimingSummary whole = stats.frame_summary();
  spdlog::info(
      "{} frames ({:.1f} s simulated): frame p50 {:.3f} ms, p99 {:.3f} ms, max {:.3f} ms; {} over the "
      "{:.1f} ms budget",
      ran, frame_loop.time_s(), whole.p50_ms, whole.p99_ms, whole.max_ms, stats.frames_over_budget(), stats.budget_ms());

  if (!stats_path.empty()) {
    nlohmann::json j = stats.to_json();
    j["scene"] = scene_path;
    j["rate_hz"] = loop.rate_hz;
    std::ofstream out(stats_path);
    out << j.dump(2) << '\n';
    out.close();
    if (!out) {
      spdlog::error("cannot write statistics to {}", stats_path);
      return EXIT_FAILURE;
    }
    spdlog::info("statistics written to {}", stats_path);
  }
  const std::uint64_t validation = (*renderer)->validation_messages();
  if (validation > 0) spdlog::warn("{} Vulkan validation message(s)", validation);
  return capture_failed ? EXIT_FAILURE : EXIT_SUCCESS;
}
