// rhot-eval stars: marker stars moving through the volume, identified and tracked, against the truth.

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
#include "tracking/filter/PoseKalman.h"
#include "tracking/rigid/StarTracker.h"
#include "tracking/sim/Realism.h"
#include "tracking/sim/SimulatedRig.h"

#include "tools/eval/Eval.h"

namespace rhot::eval {

namespace {

// The matched points of a frame, each with the simulated body it belongs to (-1: none, or
// several), and per body the points that are cleanly its.
struct LabelledPoints {
  std::vector<Eigen::Vector3d> points;
  std::vector<int> body;
  std::vector<int> clean;
};

LabelledPoints label_points(const rhot::RigFrame& frame, const std::vector<rhot::MatchedPoint>& matched, int bodies) {
  LabelledPoints out;
  out.clean.assign(static_cast<std::size_t>(bodies), 0);
  for (const rhot::MatchedPoint& m : matched) {
    out.points.push_back(m.point.position_world);
    // Markers of one star lie millimetres apart, so a point may mix two markers of one body: it is
    // still that body's.
    int body = -2;
    for (std::size_t k = 0; k < m.observations.size() && body != -1; ++k) {
      const int marker = frame.cameras[static_cast<std::size_t>(m.observations[k].camera)]
                             .detections[static_cast<std::size_t>(m.detection[k])]
                             .truth_marker;
      const int b = marker < 0 ? -1 : frame.truth_marker_body[static_cast<std::size_t>(marker)];
      body = (body == -2 || body == b) ? b : -1;
    }
    if (body < 0) {
      // Detections of markers of different bodies (two stars passing close): the body of the true
      // marker the point lies at, if it lies within a millimetre of one.
      body = -1;
      double nearest = 0.001;
      for (std::size_t t = 0; t < frame.truth_position_m.size(); ++t) {
        const double d = (frame.truth_position_m[t] - m.point.position_world).norm();
        if (d < nearest) {
          nearest = d;
          body = frame.truth_marker_body[t];
        }
      }
    }
    out.body.push_back(body);
    if (body >= 0) ++out.clean[static_cast<std::size_t>(body)];
  }
  return out;
}

// Whether a tracked star stands at its own body's markers only: at least one point of its body,
// none of another's.
bool at_its_own_markers(const rhot::TrackedStar& t, const rhot::RigFrame& frame, const std::vector<Eigen::Vector3d>& points,
                        const std::vector<int>& point_body) {
  bool other = false;
  bool own = false;
  for (const int p : t.point) {
    if (p < 0) continue;
    // A point within a millimetre of one of the star's own markers is the star's, whichever
    // marker's detections it was built from (two bodies' markers can meet in space).
    int body = point_body[static_cast<std::size_t>(p)];
    for (std::size_t k = 0; k < frame.truth_position_m.size(); ++k) {
      if (frame.truth_marker_body[k] == t.star && (frame.truth_position_m[k] - points[static_cast<std::size_t>(p)]).norm() < 0.001)
        body = t.star;
    }
    other = other || (body >= 0 && body != t.star);
    own = own || body == t.star;
  }
  return own && !other;
}

// The reported pose's error against the truth, squared and weighed by its covariance (the
// normalised estimation error squared): 6 on average where the covariance is honest.
double pose_nees(const rhot::TrackedStar& t, const rhot::Rigid3d& truth) {
  const Eigen::Matrix<double, 6, 1> e = rhot::pose_error(t.world_from_star, truth);
  return e.dot(t.covariance.ldlt().solve(e));
}

// What rhot-eval stars counts: identities of every measured star, poses of every reported one.
struct StarTally {
  long identifiable = 0;    // body-frames with three or more of the body's markers triangulated
  long correct = 0;         // ... among them, the body's star measured at the body's markers
  long wrong = 0;           // a star measured at another body's markers
  long measured = 0;        // body-frames measured (identified, certain or not)
  long reported = 0;        // ... reported as seen (the filtered pose certain)
  long reported_wrong = 0;  // ... more than 10 mm or 5 degrees from the truth
  double fit_position2 = 0, fit_rotation2 = 0, filtered_position2 = 0, filtered_rotation2 = 0;  // every measured frame
  double position2 = 0, rotation2 = 0, nees = 0;                                                // reported frames
  std::vector<double> position_sigma, rotation_sigma;

  void add(const rhot::TrackedStar& t, const rhot::RigFrame& frame, const LabelledPoints& labelled) {
    if (!t.measured_now()) return;
    ++measured;
    if (!at_its_own_markers(t, frame, labelled.points, labelled.body)) {
      ++wrong;
      return;
    }
    if (labelled.clean[static_cast<std::size_t>(t.star)] >= 3) ++correct;
    const rhot::Rigid3d& truth = frame.truth_world_from_body[static_cast<std::size_t>(t.star)];
    const double angle = Eigen::AngleAxisd(t.world_from_star.rotation * truth.rotation.conjugate()).angle();
    const double fit_angle = Eigen::AngleAxisd(t.measured.rotation * truth.rotation.conjugate()).angle();
    const double position = (t.world_from_star.translation - truth.translation).norm();
    fit_position2 += (t.measured.translation - truth.translation).squaredNorm();
    fit_rotation2 += fit_angle * fit_angle;
    filtered_position2 += position * position;
    filtered_rotation2 += angle * angle;
    position_sigma.push_back(rhot::largest_sigma(t.covariance.topLeftCorner<3, 3>()));
    rotation_sigma.push_back(rhot::largest_sigma(t.covariance.bottomRightCorner<3, 3>()));
    if (!t.seen_now()) return;
    ++reported;
    if (position > 0.010 || angle > 5.0 * std::numbers::pi / 180.0) ++reported_wrong;
    position2 += position * position;
    rotation2 += angle * angle;
    nees += pose_nees(t, truth);
  }

  void put(nlohmann::json& j) const {
    const auto per = [](double sum, long n) { return n > 0 ? sum / static_cast<double>(n) : 0.0; };
    constexpr double kDeg = 180.0 / std::numbers::pi;
    j["identifiable_body_frames"] = identifiable;
    j["correct_id_fraction"] = per(static_cast<double>(correct), identifiable);
    j["wrong_id_count"] = wrong;
    j["measured_body_frames"] = measured;
    j["reported_body_frames"] = reported;
    j["certain_fraction"] = per(static_cast<double>(reported), measured);
    j["reported_wrong_fraction"] = per(static_cast<double>(reported_wrong), reported);
    j["position_rms_mm"] = 1000.0 * std::sqrt(per(position2, reported));
    j["rotation_rms_deg"] = kDeg * std::sqrt(per(rotation2, reported));
    j["pose_nees_mean"] = per(nees, reported);
    j["measured_fit_position_rms_mm"] = 1000.0 * std::sqrt(per(fit_position2, measured));
    j["measured_fit_rotation_rms_deg"] = kDeg * std::sqrt(per(fit_rotation2, measured));
    j["measured_filtered_position_rms_mm"] = 1000.0 * std::sqrt(per(filtered_position2, measured));
    j["measured_filtered_rotation_rms_deg"] = kDeg * std::sqrt(per(filtered_rotation2, measured));
    j["position_sigma_median_mm"] = 1000.0 * percentile(position_sigma, 0.5);
    j["rotation_sigma_median_deg"] = kDeg * percentile(rotation_sigma, 0.5);
  }
};

}  // namespace

// Marker stars moving through the volume (25 of a set by default), matched, triangulated and
// tracked; identities against the truth, poses against the true poses.
int stars(const std::string& rig_file, const std::string& set_file, int bodies, const WorldFlags& world_flags, int frames, unsigned seed,
          const std::vector<double>& volume, const std::vector<double>& volume_centre, int threads) {
  const auto world = world_settings(world_flags);
  if (!world) {
    std::cerr << "rhot-eval: " << world.error() << "\n";
    return 1;
  }
  const auto rig = rhot::load_rig(rig_file);
  if (!rig) {
    std::cerr << "rhot-eval: " << rig.error() << "\n";
    return 1;
  }
  const auto set = rhot::load_star_set(set_file);
  if (!set) {
    std::cerr << "rhot-eval: " << set.error() << "\n";
    return 1;
  }
  if (bodies > static_cast<int>(set->stars.size())) {
    std::cerr << "rhot-eval: --bodies " << bodies << ": " << set_file << " has only " << set->stars.size() << " stars\n";
    return 1;
  }
  const Box box = evaluation_box(*rig, volume, volume_centre);
  const auto motions = rhot::random_motions(bodies, box.centre - box.size / 2, box.centre + box.size / 2, seed + 1);
  std::vector<rhot::SimulatedBody> simulated;
  for (int b = 0; b < bodies; ++b) {
    rhot::SimulatedBody body;
    body.motion = motions[static_cast<std::size_t>(b)];
    for (const Eigen::Vector3d& m : set->stars[static_cast<std::size_t>(b)].markers_mm) body.markers_body_m.push_back(m * 1e-3);
    simulated.push_back(body);
  }
  const rhot::SimulatedRigSettings settings = world->rig_settings(seed);
  rhot::SimulatedRig sim(*rig, {}, settings);
  sim.set_bodies(simulated);
  // The tracker knows the stars in the scene, as a scene file tells it.
  rhot::StarSet in_use = *set;
  in_use.stars.resize(static_cast<std::size_t>(bodies));
  rhot::StarTracker tracker{rhot::StarLibrary(in_use)};
  rhot::PixelSigmaEstimate pixel_sigma;
  // The tracker's rig: the truth, or as an imperfect calibration has it.
  const rhot::CameraRig tracker_rig = rhot::perturbed_rig(*rig, world->calib_error_px, seed);

  rhot::JobPool jobs(rhot::threads_or_all(threads));
  StarTally tally;
  std::vector<double> ms;
  const rhot::RigMatcher matcher(tracker_rig);
  for (int f = 0; f < frames; ++f) {
    if (world->occluding_bodies) {
      // Each star stands on an object that hides markers: a 6 cm cube under the star's base.
      std::vector<rhot::Occluder> objects;
      const double t = static_cast<double>(f) / settings.rate_hz;
      for (const rhot::SimulatedBody& b : simulated) {
        const rhot::Rigid3d pose = b.motion.world_from_body(t);
        objects.push_back(rhot::Occluder::box(pose * Eigen::Vector3d(0, 0, -0.031), pose.rotation, Eigen::Vector3d(0.03, 0.03, 0.03)));
      }
      sim.set_occluders(objects);
    }
    const rhot::RigFrame frame = sim.next();
    const std::vector<rhot::MatchedPoint> matched = matcher.match(frame, rhot::match_settings_for(pixel_sigma.sigma_px()), &jobs);
    const LabelledPoints labelled = label_points(frame, matched, bodies);
    const auto start = std::chrono::steady_clock::now();
    const std::vector<double> sigmas = rhot::point_sigmas_m(matched, pixel_sigma.update(matched));
    const auto& tracked = tracker.update(frame.time_s, labelled.points, sigmas);
    ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
    for (int b = 0; b < bodies; ++b) tally.identifiable += labelled.clean[static_cast<std::size_t>(b)] >= 3 ? 1 : 0;
    for (const rhot::TrackedStar& t : tracked) tally.add(t, frame, labelled);
    if (frames >= 20 && (f + 1) % (frames / 10) == 0) std::cerr << "rhot-eval: frame " << f + 1 << " of " << frames << "\n";
  }
  nlohmann::json j;
  j["rig"] = rig_file;
  j["set"] = set_file;
  j["bodies"] = bodies;
  j["world"] = world_json(*world, world_flags.world);
  j["frames"] = frames;
  j["seed"] = seed;
  j["threads"] = jobs.threads();
  j["volume_centre_m"] = {box.centre.x(), box.centre.y(), box.centre.z()};
  j["volume_size_m"] = {box.size.x(), box.size.y(), box.size.z()};
  tally.put(j);
  j["median_ms"] = percentile(ms, 0.5);
  j["p99_ms"] = percentile(ms, 0.99);
  std::cout << j.dump(2) << "\n";
  return 0;
}

}  // namespace rhot::eval
