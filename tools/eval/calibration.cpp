// rhot-eval calibration: a simulated wand session calibrated from unknown extrinsics (intrinsics
// given), compared with the rig that took it.

#include <chrono>
#include <cmath>
#include <iostream>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

#include "base/Jobs.h"
#include "tools/eval/Eval.h"
#include "tracking/calib/RigMerge.h"
#include "tracking/calib/Similarity.h"
#include "tracking/calib/WandCalibration.h"
#include "tracking/camera/RigFile.h"
#include "tracking/sim/CalibrationSessions.h"

namespace rhot::eval {

int calibration(const std::string& rig_file, double length_mm, double sigma, int frames, unsigned seed, double dropout, int threads) {
  const auto truth = load_rig(rig_file);
  if (!truth) {
    std::cerr << "rhot-eval: " << truth.error() << "\n";
    return 1;
  }
  WandSession session;
  session.frames = frames;
  session.wand_length_m = length_mm / 1000.0;
  const TrackingVolume box = session_box(*truth);
  session.box_centre_m = box.centre_m;
  session.box_size_m = box.size_m;
  SessionNoise noise;
  noise.rig.sigma_px = sigma;
  noise.rig.seed = seed;
  noise.rig.dropout = dropout;
  if (const auto ok = noise.rig.check(); !ok) {
    std::cerr << "rhot-eval: " << ok.error() << "\n";
    return 1;
  }
  const Detections d = simulate_wand_session(*truth, session, noise);
  WandSettings settings;
  settings.wand_length_m = session.wand_length_m;
  settings.threads = threads_or_all(threads);
  const auto start = std::chrono::steady_clock::now();
  const auto result = calibrate_wand(*truth, d, settings);  // the truth's poses are ignored
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (!result) {
    std::cerr << "rhot-eval: " << result.error() << "\n";
    return 1;
  }
  // After the similarity that best maps the estimated camera centres onto the true ones.
  std::vector<Eigen::Vector3d> from, to;
  for (std::size_t c = 0; c < truth->cameras.size(); ++c) {
    from.push_back(result->rig.cameras[c].centre_world());
    to.push_back(truth->cameras[c].centre_world());
  }
  // Two cameras' centres leave the rotation about their baseline free: then their orientations
  // fix it too (the merge's alignment).
  std::optional<Similarity3> fit = fit_similarity(from, to, true);
  if (!fit) {
    if (const auto merged = merge_rigs(*truth, result->rig, MergeSettings{}); merged) fit = merged->report.a_from_b;
  }
  double centre_sq = 0, rotation_max = 0;
  for (std::size_t c = 0; c < truth->cameras.size() && fit; ++c) {
    const Camera moved = transform_camera(result->rig.cameras[c], *fit);
    centre_sq += (moved.centre_world() - truth->cameras[c].centre_world()).squaredNorm();
    rotation_max =
        std::max(rotation_max, moved.cam_from_world.rotation.angularDistance(truth->cameras[c].cam_from_world.rotation) * 180.0 / M_PI);
  }
  const WandReport& r = result->report;
  int observations = 0;
  for (const auto& c : r.cameras) observations += c.inliers;
  const double parameters = 3.0 * r.points + 6.0 * static_cast<double>(truth->cameras.size()) - 7.0;
  const double floor_px = sigma * std::sqrt(2.0) * std::sqrt(1.0 - parameters / (2.0 * observations));
  nlohmann::json j;
  j["rig"] = rig_file;
  j["frames"] = frames;
  j["threads"] = settings.threads;
  j["sigma_px"] = sigma;
  j["dropout"] = dropout;
  j["wand_mm"] = length_mm;
  j["seconds"] = seconds;
  j["centre_rms_mm"] = fit ? std::sqrt(centre_sq / static_cast<double>(truth->cameras.size())) * 1000.0 : -1.0;
  j["rotation_max_deg"] = rotation_max;
  j["scale_error"] = fit ? fit->scale - 1.0 : 0.0;
  j["rms_px"] = r.rms_px;
  j["noise_floor_px"] = floor_px;
  double worst_camera = 0;
  for (const auto& c : r.cameras) worst_camera = std::max(worst_camera, std::abs(c.rms_px / floor_px - 1.0));
  j["worst_camera_rms_vs_floor"] = worst_camera;
  j["wand_rms_mm"] = r.wand_rms_mm;
  j["wand_mean_mm"] = r.wand_mean_mm;
  j["wand_rms_mm_true_rig"] = wand_length_rms_mm(*truth, d, session.wand_length_m);
  j["points"] = r.points;
  j["outliers"] = r.outliers;
  std::cout << j.dump(2) << "\n";
  return 0;
}

}  // namespace rhot::eval
