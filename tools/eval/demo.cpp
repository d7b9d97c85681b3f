// rhot-eval demo: the demo's first pickup with the cube at random spots on the table
// (engine/sim/DemoPickups.h), through tracked or perfect hands.

#include <iostream>
#include <string>
#include <vector>

#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>
#include <nlohmann/json.hpp>

#include "engine/scene/SceneLoader.h"
#include "base/Jobs.h"
#include "engine/sim/DemoPickups.h"

#include "tools/eval/Eval.h"

namespace rhot::eval {

int demo(const std::string& scene_file, int placements, unsigned seed, const WorldFlags& world_flags, const std::string& hands, int frames,
         int threads) {
  spdlog::set_default_logger(spdlog::stderr_color_mt("rhot-eval"));
  spdlog::set_level(spdlog::level::warn);
  const auto world = world_settings(world_flags);
  if (!world) {
    std::cerr << "rhot-eval: " << world.error() << "\n";
    return 1;
  }
  const auto scene = rhot::load_scene_file(scene_file);
  if (!scene) {
    std::cerr << "rhot-eval: " << scene.error().to_string() << "\n";
    return 1;
  }
  const auto spots = rhot::pickup_spots(*scene, placements, seed);
  if (!spots) {
    std::cerr << "rhot-eval: " << scene_file << ": " << spots.error() << "\n";
    return 1;
  }
  rhot::DemoSettings settings;
  settings.asset_dir = RHOT_ASSET_DIR;
  settings.world = *world;
  settings.sigma_px = world->sigma_px;
  settings.perfect_hands = hands == "perfect";
  settings.threads = threads;
  nlohmann::json j;
  j["scene"] = scene_file;
  j["world"] = world_json(*world, world_flags.world);
  j["hands"] = hands;
  j["seed"] = seed;
  j["frames_per_placement"] = frames;
  j["threads"] = rhot::threads_or_all(threads);
  int successes = 0, confusion = 0;
  long seen = 0, wrong = 0;
  double lift_sum = 0.0;
  for (std::size_t i = 0; i < spots->size(); ++i) {
    settings.seed = seed + static_cast<unsigned>(i);
    const auto r = rhot::run_pickup(*scene, (*spots)[i], settings, frames);
    if (!r) {
      std::cerr << "rhot-eval: " << r.error() << "\n";
      return 1;
    }
    std::cerr << "rhot-eval: placement " << (i + 1) << " of " << spots->size() << " at x " << r->spot_xz.x() << " z " << r->spot_xz.y()
              << ": "
              << (r->success   ? "lifted"
                  : r->grasped ? "grasped, not lifted"
                               : "not grasped")
              << "\n";
    successes += r->success ? 1 : 0;
    confusion += r->hand_confusion_frames;
    seen += r->hand_frames_seen;
    wrong += r->reported_wrong_frames;
    lift_sum += r->lift_m;
    j["placements"].push_back({{"x_m", r->spot_xz.x()},
                               {"z_m", r->spot_xz.y()},
                               {"grasped", r->grasped},
                               {"success", r->success},
                               {"lift_mm", 1000.0 * r->lift_m},
                               {"hand_confusion_frames", r->hand_confusion_frames},
                               {"reported_wrong_frames", r->reported_wrong_frames}});
  }
  const auto n = static_cast<double>(spots->size());
  j["grasp_success_fraction"] = successes / n;
  j["lift_mean_mm"] = 1000.0 * lift_sum / n;
  j["hand_confusion_frames"] = confusion;
  j["reported_wrong_fraction"] = seen > 0 ? static_cast<double>(wrong) / static_cast<double>(seen) : 0.0;
  std::cout << j.dump(2) << "\n";
  return 0;
}

}  // namespace rhot::eval
