// rhot-eval wand: a two-marker wand of known length waved through the volume.

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

#include "tools/eval/Eval.h"

namespace rhot::eval {

// A two-marker wand of known length waved through the volume; the measured length per frame
// against the true one (the Wiimote thesis's accuracy test).
int wand(const std::string& rig_file, double length_mm, double sigma, int frames, unsigned seed, double dropout,
         const std::vector<double>& volume, const std::vector<double>& volume_centre, int threads) {
  const auto rig = rhot::load_rig(rig_file);
  if (!rig) {
    std::cerr << "rhot-eval: " << rig.error() << "\n";
    return 1;
  }
  const Box box = evaluation_box(*rig, volume, volume_centre);
  const Eigen::Vector3d centre = box.centre;
  const Eigen::Vector3d half = box.size / 2;
  const auto ends = rhot::wand_trajectories(length_mm / 1000.0, centre - half, centre + half);
  rhot::SimulatedRigSettings settings;
  settings.sigma_px = sigma;
  settings.dropout = dropout;
  settings.seed = seed;
  if (const auto ok = settings.check(); !ok) {
    std::cerr << "rhot-eval: " << ok.error() << "\n";
    return 1;
  }
  rhot::SimulatedRig sim(*rig, {ends[0], ends[1]}, settings);
  rhot::JobPool jobs(rhot::threads_or_all(threads));
  double sum_abs = 0.0;
  double sum_sq = 0.0;
  double max_abs = 0.0;
  long measured = 0;
  const rhot::RigMatcher matcher(*rig);
  for (int f = 0; f < frames; ++f) {
    const rhot::RigFrame frame = sim.next();
    const auto matched = matcher.match(frame, {}, &jobs);
    // The wand is measured when exactly one point belongs wholly to each end.
    std::array<const rhot::MatchedPoint*, 2> end_point{nullptr, nullptr};
    int points_per_end[2] = {0, 0};
    for (const rhot::MatchedPoint& m : matched) {
      const int marker = rhot::truth_marker(frame, m);
      if (marker < 0) continue;
      ++points_per_end[marker];
      end_point[static_cast<std::size_t>(marker)] = &m;
    }
    if (points_per_end[0] != 1 || points_per_end[1] != 1) continue;
    const double length = 1000.0 * (end_point[0]->point.position_world - end_point[1]->point.position_world).norm();
    const double error = length - length_mm;
    sum_abs += std::abs(error);
    sum_sq += error * error;
    max_abs = std::max(max_abs, std::abs(error));
    ++measured;
  }
  nlohmann::json j;
  j["rig"] = rig_file;
  j["length_mm"] = length_mm;
  j["sigma_px"] = sigma;
  j["dropout"] = dropout;
  j["threads"] = jobs.threads();
  j["frames"] = frames;
  j["frames_measured"] = measured;
  j["volume_centre_m"] = {centre.x(), centre.y(), centre.z()};
  j["volume_size_m"] = {box.size.x(), box.size.y(), box.size.z()};
  j["mean_error_mm"] = measured > 0 ? sum_abs / static_cast<double>(measured) : 0.0;
  j["rms_error_mm"] = measured > 0 ? std::sqrt(sum_sq / static_cast<double>(measured)) : 0.0;
  j["max_error_mm"] = max_abs;
  std::cout << j.dump(2) << "\n";
  return measured > 0 ? 0 : 1;
}

}  // namespace rhot::eval
