// headless_example: a scene run by rhot's runtime offscreen, as an application built against the
// installed package, with a system of its own between tracking and physics.
//
//   headless_example [--frames N] [--png FILE]
//
// The runtime is launched by the composition root (engine/launch/Launch.h) on a source of the
// application's own: here the demo's simulated cameras photographing the demo's scripted hands
// (engine/sim); an application on real cameras names video devices or camera nodes in
// LaunchSettings instead and gives no factory. The application's system, "reach", runs after the
// tracking stages and before physics: it reads the tracked right hand and reports how close its
// index fingertip comes to the red cube. At the end it prints what the physics did with the
// hand (what it held) and, with --png, writes the left eye of the last frame.

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <memory>
#include <string>

#include "engine/app/FrameLoop.h"
#include "engine/core/Systems.h"
#include "engine/core/Transform.h"
#include "engine/core/World.h"
#include "engine/launch/Launch.h"
#include "engine/render/Image.h"
#include "engine/render/Renderer.h"
#include "engine/scene/Components.h"
#include "engine/scene/SceneLoader.h"
#include "engine/sim/Demo.h"
#include "tracking/hand/HandJoints.h"
#include "tracking/sim/SimulatedRig.h"

namespace {

int fail(const std::string& what) {
  std::fprintf(stderr, "headless_example: %s\n", what.c_str());
  return EXIT_FAILURE;
}

}  // namespace

int main(int argc, char** argv) {
  unsigned long frames = 270;
  std::filesystem::path png;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--help") {
      std::printf("headless_example [--frames N] [--png FILE]: runs the default scene offscreen with a system of its own\n");
      return EXIT_SUCCESS;
    }
    if (arg == "--frames" && i + 1 < argc) {
      const std::string value = argv[++i];
      if (value.empty() || value.size() > 6 || value.find_first_not_of("0123456789") != std::string::npos || std::stoul(value) == 0) {
        return fail("--frames: expected a whole number from 1 to 999999, got '" + value + "'");
      }
      frames = std::stoul(value);
    } else if (arg == "--png" && i + 1 < argc) {
      png = argv[++i];
    } else {
      return fail("unknown argument '" + arg + "' (--help)");
    }
  }

  const std::filesystem::path assets = RHOT_ASSET_DIR;  // the installed package's rhot_ASSET_DIR
  auto scene = rhot::load_scene_file(assets / "scenes" / "default.json");
  if (!scene) return fail(scene.error().to_string());

  rhot::RendererSettings render;
  render.eye_width_px = 320;
  render.eye_height_px = 360;
  auto renderer = rhot::Renderer::create(render);  // offscreen: no window
  if (!renderer) return fail("no renderer: " + renderer.error());

  // The application's own source: the demo's simulated world photographed by the rig's cameras.
  auto sim = rhot::make_demo_simulation(*scene, assets);
  if (!sim) return fail(sim.error());
  const rhot::SourceFactory simulated = [&sim](const rhot::SourceRequest& request) -> std::expected<rhot::CustomSource, std::string> {
    auto rig = std::make_unique<rhot::SimulatedRig>(request.rig, std::vector<rhot::Trajectory>{}, rhot::SimulatedRigSettings{});
    rig->set_world(sim->world);
    rhot::CustomSource out;
    out.source = std::move(rig);
    return out;
  };
  rhot::LaunchSettings settings;
  settings.asset_dir = assets;
  auto launched = rhot::Launch::create(*scene, renderer->get(), settings, simulated);
  if (!launched) return fail(launched.error());
  rhot::Runtime& runtime = (*launched)->runtime();

  // The application's system: after the tracking stages ("hands"), before physics.
  const rhot::Entity cube = rhot::find_named(runtime.world(), "cube-red");
  double closest_m = std::numeric_limits<double>::infinity();
  unsigned long seen_frames = 0;
  runtime.add_stage("hands", {"reach", [&](double) {
                                const rhot::HandInput& right = runtime.tracking().results().hands[1];
                                const rhot::Transform* at = runtime.world().find<rhot::Transform>(cube);
                                if (!right.seen || !at) return;
                                ++seen_frames;
                                const Eigen::Vector3d tip = right.joints_world[static_cast<std::size_t>(rhot::HandJoint::kIndexTip)];
                                const Eigen::Vector3d centre(at->position.x, at->position.y, at->position.z);
                                closest_m = std::min(closest_m, (tip - centre).norm());
                              }});
  rhot::Systems systems;
  runtime.add_systems(systems, "");
  if (const auto built = systems.build(); !built) return fail("systems: " + built.error());
  rhot::FrameLoop loop(runtime.world(), systems, rhot::FrameLoopSettings{});
  const std::uint64_t ran = loop.run(frames);

  std::printf("ran %llu frames (%.2f s of the scene); the right hand was tracked in %lu\n", static_cast<unsigned long long>(ran),
              static_cast<double>(ran) / 90.0, seen_frames);
  if (seen_frames > 0) std::printf("the right index fingertip came within %.0f mm of the red cube's centre\n", 1000.0 * closest_m);
  const rhot::HandBody* body = runtime.hand_body(rhot::HandSide::kRight);
  std::printf("the right hand holds %s\n", body && body->holding ? "an object" : "nothing");
  if (!png.empty()) {
    if (auto written = rhot::write_png((*renderer)->read_eye(0), png); !written) return fail(written.error());
    std::printf("left eye of the last frame: %s\n", png.string().c_str());
  }
  return seen_frames > 0 ? EXIT_SUCCESS : fail("the right hand was never tracked");
}
