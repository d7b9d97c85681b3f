// rhot-eval grasp: scripted grasp scenarios through the physics (engine/sim/GraspScenarios.h).

#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <expected>
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

#include "tools/eval/Eval.h"

namespace rhot::eval {

namespace {

// Tracked hands: the rig, both hands' shipped layouts and the simulated world.
std::expected<rhot::ScenarioCameras, std::string> scenario_cameras(const GraspArgs& args) {
  const auto world = world_settings(args.world);
  if (!world) return std::unexpected(world.error());
  auto rig = rhot::load_rig(args.rig_file);
  if (!rig) return std::unexpected(rig.error());
  rhot::ScenarioCameras cameras{std::move(*rig), {}, *world, args.seed, args.threads};
  for (std::size_t h = 0; h < 2; ++h) {
    auto layout =
        rhot::load_hand_layout(std::string(RHOT_ASSET_DIR) + (h == 0 ? "/hands/low-cost-left.json" : "/hands/low-cost-right.json"));
    if (!layout) return std::unexpected(layout.error());
    cameras.layouts[h] = std::move(*layout);
  }
  return cameras;
}

}  // namespace

// Scripted grasp scenarios through the real physics (engine/sim/GraspScenarios.h).
int grasp(const GraspArgs& args) {
  std::vector<std::string_view> names;
  for (const std::string_view n : rhot::grasp_scenario_names()) {
    if (args.scenario == "all" || args.scenario == n) names.push_back(n);
  }
  if (names.empty()) {
    std::string list;
    for (const std::string_view n : rhot::grasp_scenario_names()) list += std::string(n) + ", ";
    std::cerr << "rhot-eval: --scenario " << args.scenario << ": no such scenario (" << list << "all)\n";
    return 1;
  }
  std::optional<rhot::ScenarioCameras> cameras;
  if (args.hands == "tracked") {
    auto made = scenario_cameras(args);
    if (!made) {
      std::cerr << "rhot-eval: " << made.error() << "\n";
      return 1;
    }
    cameras = std::move(*made);
  }
  nlohmann::json j;
  std::vector<double> steps;
  int lifts = 0, lifted = 0;
  long seen = 0, wrong = 0, confusion = 0;
  double max_slip = 0.0;
  std::optional<double> throw_error;
  GraspComparison grasps;
  for (const std::string_view name : names) {
    std::cerr << "rhot-eval: grasp scenario " << name << "\n";
    const auto r = rhot::run_grasp_scenario(name, nullptr, cameras ? &*cameras : nullptr);
    if (!r) {
      std::cerr << "rhot-eval: " << r.error() << "\n";
      return 1;
    }
    nlohmann::json s;
    if (cameras) {
      // The same scenario with perfect hands: the grasps the tracked ones should have made.
      const auto reference = rhot::run_grasp_scenario(name, nullptr, nullptr);
      if (!reference) {
        std::cerr << "rhot-eval: " << reference.error() << "\n";
        return 1;
      }
      const double end_s = static_cast<double>(std::max(r->frames, reference->frames)) / 90.0;  // the scenarios step at 90 Hz
      const GraspComparison c = compare_grasps(grasp_spans(r->events, end_s), grasp_spans(reference->events, end_s));
      grasps.add(c);
      c.put(s);
    }
    s["grasped"] = r->grasped;
    s["lift_mm"] = 1000.0 * r->lift_m;
    s["max_slip_mm"] = 1000.0 * r->max_slip_m;
    s["held_s"] = r->held_s;
    s["released"] = r->released;
    s["fell_after_release"] = r->fell_after_release;
    s["handed_over"] = r->handed_over;
    s["pushed_mm"] = 1000.0 * r->pushed_m;
    s["successes"] = r->successes;
    s["frames"] = r->frames;
    nlohmann::json events = nlohmann::json::array();
    for (const rhot::InteractionEvent& e : r->events) {
      if (e.type == rhot::InteractionEventType::kHoverBegin || e.type == rhot::InteractionEventType::kHoverEnd) continue;
      nlohmann::json ev = {{"t_s", e.time_s}, {"type", rhot::event_name(e.type)}, {"object", e.object.index}};
      if (!e.reason.empty()) ev["reason"] = e.reason;  // why a grasp began or ended, as the overlay says it
      if (e.hand) ev["hand"] = *e.hand == rhot::HandSide::kLeft ? "left" : "right";
      if (!e.interaction.empty()) ev["interaction"] = e.interaction;
      events.push_back(ev);
    }
    s["events"] = events;
    if (cameras) {
      s["hand_frames_seen"] = r->hand_frames_seen;
      s["reported_wrong_frames"] = r->reported_wrong_frames;
      s["hand_confusion_frames"] = r->hand_confusion_frames;
      s["fingertip_mean_mm"] = r->fingertip_mean_mm;
      seen += r->hand_frames_seen;
      wrong += r->reported_wrong_frames;
      confusion += r->hand_confusion_frames;
    }
    s["step_p50_ms"] = percentile(r->step_ms, 0.5);
    s["step_p99_ms"] = percentile(r->step_ms, 0.99);
    if (name == "throw") {
      s["hand_speed_mps"] = r->hand_speed_mps;
      s["throw_velocity_error_pct"] = 100.0 * r->throw_velocity_error;
      throw_error = 100.0 * r->throw_velocity_error;
    }
    // A lift succeeds when the object rose 10 cm and stayed held 2 s.
    if (name == "lift" || name == "pinch" || name == "hidden-markers") {
      ++lifts;
      const bool ok = r->grasped && r->lift_m >= 0.1 && r->held_s >= 2.0;
      lifted += ok ? 1 : 0;
      s["lift_success"] = ok;
    }
    // Slip while one hand holds (a hand-over's second hand squeezes the object on purpose).
    if (r->grasped && name != "hand-over") max_slip = std::max(max_slip, 1000.0 * r->max_slip_m);
    steps.insert(steps.end(), r->step_ms.begin(), r->step_ms.end());
    j["scenarios"][std::string(name)] = s;
  }
  if (lifts > 0) j["lift_success_fraction"] = static_cast<double>(lifted) / lifts;
  j["hands"] = args.hands;
  if (cameras) {
    j["rig"] = args.rig_file;
    j["world"] = world_json(cameras->world, args.world.world);
    j["seed"] = args.seed;
    j["threads"] = rhot::threads_or_all(args.threads);
    j["hand_confusion_frames"] = confusion;
    grasps.put(j);
    j["reported_wrong_fraction"] = static_cast<double>(wrong) / static_cast<double>(std::max(1L, seen));
  }
  j["max_slip_mm"] = max_slip;
  if (throw_error) j["throw_velocity_error_pct"] = *throw_error;
  j["step_p50_ms"] = percentile(steps, 0.5);
  j["step_p99_ms"] = percentile(steps, 0.99);
  std::cout << j.dump(2) << "\n";
  return 0;
}

}  // namespace rhot::eval
