// rhot-eval triangulation: markers wandering through the volume, matched and triangulated,
// against the truth and the Cramer-Rao bound of each point.

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

int triangulation(const std::string& rig_file, double sigma, int frames, unsigned seed, int markers, double dropout,
                  const std::vector<double>& volume, const std::vector<double>& volume_centre, bool uniform, int threads, bool follow) {
  const auto rig = rhot::load_rig(rig_file);
  if (!rig) {
    std::cerr << "rhot-eval: " << rig.error() << "\n";
    return 1;
  }
  if (rig->cameras.size() < 2) {
    std::cerr << "rhot-eval: " << rig_file << ": triangulation needs at least two cameras\n";
    return 1;
  }
  const Box box = evaluation_box(*rig, volume, volume_centre);
  const Eigen::Vector3d centre = box.centre;
  const Eigen::Vector3d half = box.size / 2;
  rhot::SimulatedRigSettings settings;
  settings.sigma_px = sigma;
  settings.dropout = dropout;
  settings.seed = seed;
  if (const auto ok = settings.check(); !ok) {
    std::cerr << "rhot-eval: " << ok.error() << "\n";
    return 1;
  }
  rhot::SimulatedRig sim(*rig,
                         uniform ? rhot::scattered_markers(markers, centre - half, centre + half, seed + 1)
                                 : rhot::random_trajectories(markers, centre - half, centre + half, seed + 1),
                         settings);

  rhot::JobPool jobs(rhot::threads_or_all(threads));
  double sum_error2 = 0.0;
  double sum_bound2 = 0.0;
  long points = 0;
  long findable = 0;
  long found = 0;
  long ghosts = 0;
  long mixed = 0;
  long duplicates = 0;  // a second point of a marker in one frame (found counts each marker once)
  std::vector<char> has_point;
  std::vector<double> ms;
  std::vector<double> errors_mm;  // every found marker's 3D error
  // Frame after frame as the runtime matches (RigMatcher::match_frame), following the last
  // frame's points unless --no-follow.
  rhot::RigMatcher matcher(*rig);
  rhot::MatchSettings match_settings;
  match_settings.follow_points = follow;
  for (int f = 0; f < frames; ++f) {
    const rhot::RigFrame frame = sim.next();
    const auto start = std::chrono::steady_clock::now();
    const auto matched = matcher.match_frame(frame, match_settings, &jobs);
    ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
    std::vector<int> seen_by(frame.truth_position_m.size(), 0);
    for (const rhot::CameraFrame& cf : frame.cameras) {
      for (const rhot::Detection& d : cf.detections) ++seen_by[static_cast<std::size_t>(d.truth_marker)];
    }
    for (const int n : seen_by) findable += n >= 2 ? 1 : 0;
    has_point.assign(frame.truth_position_m.size(), 0);
    for (const rhot::MatchedPoint& m : matched) {
      const int marker = rhot::truth_marker(frame, m);
      if (marker < 0) {
        // Detections of more than one marker: a mix-up when the point still lies at a marker (two
        // markers' projections nearly coincide in a camera), a ghost when it lies at none.
        double nearest_m = std::numeric_limits<double>::infinity();
        for (const Eigen::Vector3d& t : frame.truth_position_m) nearest_m = std::min(nearest_m, (t - m.point.position_world).norm());
        ++(nearest_m <= kGhostDistance_m ? mixed : ghosts);
        continue;
      }
      if (has_point[static_cast<std::size_t>(marker)] != 0) {
        ++duplicates;
        continue;
      }
      has_point[static_cast<std::size_t>(marker)] = 1;
      ++found;
      const Eigen::Vector3d truth = frame.truth_position_m[static_cast<std::size_t>(marker)];
      const auto cov = rhot::crlb_covariance(*rig, truth, m.point.cameras, sigma);
      if (!cov) continue;
      sum_error2 += (m.point.position_world - truth).squaredNorm();
      errors_mm.push_back(1000.0 * (m.point.position_world - truth).norm());
      sum_bound2 += cov->trace();
      ++points;
    }
    if (frames >= 20 && (f + 1) % (frames / 10) == 0) std::cerr << "rhot-eval: frame " << f + 1 << " of " << frames << "\n";
  }
  const double rms_mm = points > 0 ? 1000.0 * std::sqrt(sum_error2 / static_cast<double>(points)) : 0.0;
  const double crlb_mm = points > 0 ? 1000.0 * std::sqrt(sum_bound2 / static_cast<double>(points)) : 0.0;
  nlohmann::json j;
  j["rig"] = rig_file;
  j["cameras"] = rig->cameras.size();
  j["sigma_px"] = sigma;
  j["dropout"] = dropout;
  j["frames"] = frames;
  j["markers"] = markers;
  j["seed"] = seed;
  j["threads"] = jobs.threads();
  j["follow"] = follow;
  j["volume_centre_m"] = {centre.x(), centre.y(), centre.z()};
  j["volume_size_m"] = {box.size.x(), box.size.y(), box.size.z()};
  j["spread"] = uniform ? "uniform" : "wander";
  j["rms_mm"] = rms_mm;
  j["crlb_mm"] = crlb_mm;
  j["ratio"] = crlb_mm > 0.0 ? rms_mm / crlb_mm : 0.0;
  // The error's distribution over the markers found, what rhot-plan predicts (docs/planning.md).
  j["error_median_mm"] = percentile(errors_mm, 0.5);
  j["error_p95_mm"] = percentile(errors_mm, 0.95);
  // Markers seen by two or more cameras, per frame: what there was to find.
  j["findable_per_frame"] = static_cast<double>(findable) / static_cast<double>(frames);
  j["found_fraction"] = findable > 0 ? static_cast<double>(found) / static_cast<double>(findable) : 0.0;
  j["ghosts"] = ghosts;
  j["mixed"] = mixed;
  j["duplicates"] = duplicates;
  j["median_ms"] = percentile(ms, 0.5);
  j["p99_ms"] = percentile(ms, 0.99);
  std::cout << j.dump(2) << "\n";
  return 0;
}

}  // namespace rhot::eval
