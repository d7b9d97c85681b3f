// What rhot-eval's subcommands share: the evaluation box, percentiles.

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <map>
#include <limits>
#include <numbers>
#include <optional>
#include <string>
#include <vector>

#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>
#include <Eigen/Dense>
#include <nlohmann/json.hpp>

#include "engine/sim/GraspScenarios.h"
#include "engine/scene/SceneLoader.h"
#include "tracking/camera/RigFile.h"
#include "tracking/geometry/Matching.h"
#include "tracking/sim/HandMotions.h"
#include "tracking/hand/HandTracker.h"
#include "tracking/rigid/StarTracker.h"
#include "tracking/sim/SimulatedRig.h"

#include "engine/interact/GraspSystem.h"
#include "tools/eval/Eval.h"

namespace rhot::eval {

Box evaluation_box(const rhot::CameraRig& rig, const std::vector<double>& size, const std::vector<double>& centre) {
  Box box{rhot::axes_meeting_point(rig), Eigen::Vector3d::Ones()};
  if (rig.volume) box = {rig.volume->centre_m, rig.volume->size_m};
  if (size.size() == 3) box.size = {size[0], size[1], size[2]};
  if (centre.size() == 3) box.centre = {centre[0], centre[1], centre[2]};
  return box;
}

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const auto rank = static_cast<std::size_t>(std::ceil(q * static_cast<double>(v.size())));
  return v[std::clamp<std::size_t>(rank, 1, v.size()) - 1];
}

}  // namespace rhot::eval

namespace rhot::eval {

std::expected<rhot::WorldSettings, std::string> world_settings(const WorldFlags& flags) {
  auto world = rhot::world_named(flags.world);
  if (!world) return world;
  for (const auto& [name, value] : {std::pair{"--sigma", flags.sigma},
                                    {"--dropout", flags.dropout},
                                    {"--calib-error-px", flags.calib_error_px},
                                    {"--skew-ms", flags.skew_ms},
                                    {"--marker-mm", flags.marker_mm}}) {
    // CLI11's range checks let NaN through (every comparison with it is false).
    if (value && !std::isfinite(*value)) return std::unexpected(std::string(name) + ": expected a finite number");
  }
  if (flags.sigma) world->sigma_px = *flags.sigma;
  if (flags.dropout) world->dropout = *flags.dropout;
  if (flags.strays) world->strays = *flags.strays;
  if (flags.calib_error_px) world->calib_error_px = *flags.calib_error_px;
  if (flags.skew_ms) world->camera_skew_s = *flags.skew_ms * 1e-3;
  if (flags.marker_mm) world->marker_diameter_m = *flags.marker_mm * 1e-3;
  if (flags.truth_hand) world->independent_hands = *flags.truth_hand == "independent";
  if (flags.bodies_hide) world->occluding_bodies = *flags.bodies_hide == "yes";
  if (auto ok = world->check(); !ok) return std::unexpected(ok.error());
  return world;
}

nlohmann::json world_json(const rhot::WorldSettings& w, const std::string& name) {
  return {{"name", name},
          {"sigma_px", w.sigma_px},
          {"dropout", w.dropout},
          {"strays", w.strays},
          {"marker_diameter_mm", 1000.0 * w.marker_diameter_m},
          {"camera_skew_ms", 1000.0 * w.camera_skew_s},
          {"calib_error_px", w.calib_error_px},
          {"truth_hand", w.independent_hands ? "independent" : "model"},
          {"occluding_bodies", w.occluding_bodies}};
}

std::vector<GraspSpan> grasp_spans(const std::vector<rhot::InteractionEvent>& events, double end_s) {
  std::vector<GraspSpan> spans;
  std::map<std::pair<int, std::uint32_t>, std::size_t> open;  // (hand, object) -> its span
  for (const rhot::InteractionEvent& e : events) {
    if (!e.hand || (e.type != rhot::InteractionEventType::kGrasp && e.type != rhot::InteractionEventType::kRelease)) continue;
    const std::pair<int, std::uint32_t> key{*e.hand == rhot::HandSide::kLeft ? 0 : 1, e.object.index};
    if (e.type == rhot::InteractionEventType::kGrasp) {
      open[key] = spans.size();
      spans.push_back({*e.hand, e.object.index, e.time_s, end_s, false});
    } else if (const auto it = open.find(key); it != open.end()) {
      spans[it->second].end_s = e.time_s;
      spans[it->second].released = true;
      open.erase(it);
    }
  }
  return spans;
}

GraspComparison compare_grasps(const std::vector<GraspSpan>& tracked, const std::vector<GraspSpan>& perfect) {
  GraspComparison c;
  c.cycles = static_cast<int>(perfect.size());
  c.tracked_grasps = static_cast<int>(tracked.size());
  const auto same = [](const GraspSpan& a, const GraspSpan& b) { return a.hand == b.hand && a.object == b.object; };
  for (const GraspSpan& p : perfect) {
    const bool made = std::any_of(tracked.begin(), tracked.end(), [&](const GraspSpan& g) {
      return same(g, p) && g.begin_s <= p.end_s && g.end_s >= p.begin_s - kSameMoment_s;
    });
    c.missed += made ? 0 : 1;
    // Let go late: the tracked hand that held it then still held it kSameMoment_s after the
    // perfect hand opened (a run's end counts as holding on).
    if (!made || !p.released) continue;
    double held_until = p.begin_s;
    for (const GraspSpan& g : tracked) {
      if (same(g, p) && g.begin_s <= p.end_s && g.end_s >= p.begin_s - kSameMoment_s) held_until = std::max(held_until, g.end_s);
    }
    c.late_releases += held_until > p.end_s + kSameMoment_s ? 1 : 0;
  }
  for (const GraspSpan& g : tracked) {
    // Meant: the perfect hands held the same object with the same hand at some time during it (a
    // grasp a little earlier or later than theirs is theirs).
    const bool meant = std::any_of(perfect.begin(), perfect.end(), [&](const GraspSpan& p) {
      return same(g, p) && g.begin_s <= p.end_s + kSameMoment_s && g.end_s >= p.begin_s - kSameMoment_s;
    });
    c.unintended_grasps += meant ? 0 : 1;
    if (!g.released) continue;
    // Unintended: the perfect hands held it (or took it within the same moment) and still held it
    // a moment after this release, and let go of it at no moment near it. A grasp let go at once,
    // before theirs began, is one too: the object was dropped.
    const bool held_on = std::any_of(perfect.begin(), perfect.end(), [&](const GraspSpan& p) {
      return same(g, p) && p.begin_s <= g.end_s + kSameMoment_s && p.end_s > g.end_s + kSameMoment_s;
    });
    const bool let_go_then = std::any_of(perfect.begin(), perfect.end(), [&](const GraspSpan& p) {
      return same(g, p) && p.released && std::abs(p.end_s - g.end_s) <= kSameMoment_s;
    });
    c.unintended_releases += held_on && !let_go_then ? 1 : 0;
  }
  return c;
}

void GraspComparison::add(const GraspComparison& o) {
  cycles += o.cycles;
  tracked_grasps += o.tracked_grasps;
  missed += o.missed;
  unintended_releases += o.unintended_releases;
  late_releases += o.late_releases;
  unintended_grasps += o.unintended_grasps;
}

void GraspComparison::put(nlohmann::json& j) const {
  j["grasp_cycles"] = cycles;
  j["tracked_grasps"] = tracked_grasps;
  j["missed_grasp_count"] = missed;
  j["unintended_release_count"] = unintended_releases;
  j["late_release_count"] = late_releases;
  j["unintended_grasp_count"] = unintended_grasps;
}

}  // namespace rhot::eval
