// track_example: rhot's tracker on its own, as an application built against the installed
// package (no renderer, no physics). The demo's simulated cameras (or your own, with video:)
// photograph two hands and the star-tracked objects; every half second it prints where the hands
// and objects are, and at the end how far the tracked index fingertips were from the truth.
//
//   track_example [--seconds S] [--video DEV,DEV,...]
//
// --video takes one OpenCV device, video file or image sequence per camera of the rig
// (assets/rigs/seated-4.yaml), as rhot-demo --source video: does; there is no truth then.

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "engine/hand/HandInput.h"
#include "engine/scene/SceneLoader.h"
#include "engine/sim/Demo.h"
#include "engine/tracked/LiveTracking.h"
#include "tracking/camera/RigFile.h"
#include "tracking/hand/HandJoints.h"
#include "tracking/sim/SimulatedRig.h"
#include "tracking/source/VideoSource.h"

namespace {

int fail(const std::string& what) {
  std::fprintf(stderr, "track_example: %s\n", what.c_str());
  return EXIT_FAILURE;
}

}  // namespace

int main(int argc, char** argv) {
  double seconds = 2.0;
  std::vector<std::string> video;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--help") {
      std::printf("track_example [--seconds S] [--video DEV,DEV,...]: tracks hands and objects, prints their poses\n");
      return EXIT_SUCCESS;
    }
    if (arg == "--seconds" && i + 1 < argc) {
      try {
        seconds = std::stod(argv[++i]);
      } catch (const std::exception&) {
        return fail("--seconds: expected a number of seconds, got '" + std::string(argv[i]) + "'");
      }
      if (!(seconds > 0.0 && seconds <= 3600.0)) return fail("--seconds: expected 0 < S <= 3600");
    } else if (arg == "--video" && i + 1 < argc) {
      std::stringstream list(argv[++i]);
      for (std::string dev; std::getline(list, dev, ',');) video.push_back(dev);
    } else {
      return fail("unknown argument '" + arg + "' (--help)");
    }
  }

  const std::filesystem::path assets = RHOT_ASSET_DIR;  // the installed package's rhot_ASSET_DIR
  auto scene = rhot::load_scene_file(assets / "scenes" / "default.json");
  if (!scene) return fail(scene.error().to_string());
  auto sim = rhot::make_demo_simulation(*scene, assets);  // hand layouts, star-tracked objects, simulated world
  if (!sim) return fail(sim.error());
  auto rig = rhot::load_rig(assets / "rigs" / "seated-4.yaml");
  if (!rig) return fail(rig.error());

  std::unique_ptr<rhot::FrameSource> source;
  if (!video.empty()) {
    auto opened = rhot::VideoSource::open(*rig, video, {});
    if (!opened) return fail(opened.error());
    source = std::make_unique<rhot::VideoSource>(std::move(*opened));
  } else {
    auto simulated = std::make_unique<rhot::SimulatedRig>(*rig, std::vector<rhot::Trajectory>{}, rhot::SimulatedRigSettings{});
    simulated->set_world(sim->world);
    source = std::move(simulated);
  }
  rhot::LiveTracking live(std::move(source), sim->objects, sim->layouts);
  const std::vector<rhot::TrackingStage> stages = live.stages();

  const int frames = static_cast<int>(seconds * 90.0);
  const auto tip = static_cast<std::size_t>(rhot::HandJoint::kIndexTip);
  double tip_error_sum_m = 0.0;
  int tip_errors = 0;
  for (int i = 0; i < frames; ++i) {
    const double t = i / 90.0;
    for (const rhot::TrackingStage& stage : stages) stage.run(t);
    const rhot::TrackingResults& r = live.results();
    const auto& truth = sim->world->truth();
    for (std::size_t h = 0; h < 2; ++h) {
      if (!r.hands[h].seen || video.size() > 0 || !truth) continue;
      const rhot::HandInput real = rhot::hand_input(truth->hands[h].world_from_hand, truth->hands[h].pose);
      tip_error_sum_m += (r.hands[h].joints_world[tip] - real.joints_world[tip]).norm();
      ++tip_errors;
    }
    if (i % 45 != 0) continue;
    std::printf("t %.2f s: %zu markers", t, r.points.size());
    for (std::size_t h = 0; h < 2; ++h) {
      const Eigen::Vector3d& w = r.hands[h].joints_world[static_cast<std::size_t>(rhot::HandJoint::kWrist)];
      if (r.hands[h].seen) {
        std::printf(", %s wrist (%.3f %.3f %.3f) m", h == 0 ? "left" : "right", w.x(), w.y(), w.z());
      } else {
        std::printf(", %s hand not seen", h == 0 ? "left" : "right");
      }
    }
    for (const auto& [id, pose] : r.world_from_object) {
      std::printf(", star %d at (%.3f %.3f %.3f) m", id, pose.translation.x(), pose.translation.y(), pose.translation.z());
    }
    std::printf("\n");
  }
  if (!video.empty()) return EXIT_SUCCESS;
  if (tip_errors == 0) return fail("no hand was tracked");
  std::printf("index fingertips: %.2f mm from the truth on average over %d tracked hand-frames of %d frames\n",
              1000.0 * tip_error_sum_m / tip_errors, tip_errors, frames);
  return EXIT_SUCCESS;
}
