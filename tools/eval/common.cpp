// What rhot-eval's subcommands share: the evaluation box, percentiles.

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

#include <CLI/CLI.hpp>
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

void add_world_flags(CLI::App& command, WorldFlags& flags, bool hands) {
  command.add_option("--world", flags.world, "the simulated world: ideal or realistic (docs/tracking.md); the flags below override it")
      ->capture_default_str()
      ->check(CLI::IsMember({"ideal", "realistic"}));
  command.add_option("--sigma", flags.sigma, "pixel noise, standard deviation per axis (ideal 0.3, realistic 0.5)")
      ->check(CLI::Range(1e-6, 50.0));
  command.add_option("--dropout", flags.dropout, "probability a camera misses a visible marker")->check(CLI::Range(0.0, 1.0));
  command.add_option("--strays", flags.strays, "false blobs per camera per frame, half fixed like lamps, half flickering")
      ->check(CLI::Range(0, 1000));
  command.add_option("--calib-error-px", flags.calib_error_px, "the tracker's rig is off the true one by about this reprojection error")
      ->check(CLI::Range(0.0, 20.0));
  command.add_option("--skew-ms", flags.skew_ms, "camera i exposes i times this later (unsynchronised cameras)")
      ->check(CLI::Range(-100.0, 100.0));
  command.add_option("--marker-mm", flags.marker_mm, "marker diameter: blobs merge when their discs overlap (0: never)")
      ->check(CLI::Range(0.0, 100.0));
  command
      .add_option("--bodies-hide", flags.bodies_hide,
                  "yes: the table and the objects hide markers too, not only the hands (realistic: yes)")
      ->check(CLI::IsMember({"yes", "no"}));
  if (hands) {
    command.add_option("--truth-hand", flags.truth_hand, "model (the solver's own hand) or independent (a user's own bones and angles)")
        ->check(CLI::IsMember({"model", "independent"}));
  }
}

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

}  // namespace rhot::eval
