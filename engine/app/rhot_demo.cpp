// rhot-demo: the VR demo. Loads a scene, runs the frame loop at a fixed 90 Hz step, and reports
// frame statistics. Later layers add tracking, hands, physics and the renderer to the same loop.

#include <atomic>
#include <csignal>
#include <cstdlib>
#include <fstream>
#include <string>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include "engine/app/FrameLoop.h"
#include "engine/core/Transform.h"
#include "engine/core/World.h"
#include "engine/scene/SceneLoader.h"

#ifndef RHOT_ASSET_DIR
#error "RHOT_ASSET_DIR must name the assets folder"
#endif

namespace {

std::atomic<bool> g_interrupted{false};

void on_signal(int) { g_interrupted.store(true); }

bool display_available() {
  const char* x11 = std::getenv("DISPLAY");
  const char* wayland = std::getenv("WAYLAND_DISPLAY");
  return (x11 != nullptr && *x11 != '\0') || (wayland != nullptr && *wayland != '\0');
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App cli{"rhot-demo: tracked hands and objects in VR, drawn for both eyes of a headset.\n"
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
  CLI11_PARSE(cli, argc, argv);
  spdlog::set_level(spdlog::level::from_str(log_level));

  if (!headless && !display_available()) {
    spdlog::info("no display found (DISPLAY and WAYLAND_DISPLAY are unset); running headless");
    headless = true;
  } else if (!headless) {
    spdlog::info("this build has no desktop window yet; running headless");
    headless = true;
  }
  if (headless && frames == 0) frames = 900;

  const auto scene = rhot::load_scene_file(scene_path);
  if (!scene) {
    spdlog::error("cannot load scene: {}", scene.error().to_string());
    return EXIT_FAILURE;
  }
  rhot::World world;
  const auto entities = rhot::instantiate(*scene, world);
  spdlog::info("scene {}: {} entities", scene_path, entities.size());

  rhot::Systems systems;
  systems.add({"transforms", {}, {}, [](rhot::World& w, const rhot::FrameContext&) { rhot::update_world_transforms(w); }});
  if (const auto built = systems.build(); !built) {
    spdlog::error("cannot order systems: {}", built.error());
    return EXIT_FAILURE;
  }

  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  loop.real_time = !headless;
  rhot::FrameLoop frame_loop(world, systems, loop);
  const std::uint64_t ran = frame_loop.run(frames, [] { return !g_interrupted.load(); });

  const rhot::FrameStats& stats = frame_loop.stats();
  const rhot::TimingSummary whole = stats.frame_summary();
  spdlog::info("{} frames ({:.1f} s simulated): frame p50 {:.3f} ms, p99 {:.3f} ms, max {:.3f} ms; {} over the "
               "{:.1f} ms budget",
               ran, frame_loop.time_s(), whole.p50_ms, whole.p99_ms, whole.max_ms, stats.frames_over_budget(),
               stats.budget_ms());

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
  return EXIT_SUCCESS;
}
