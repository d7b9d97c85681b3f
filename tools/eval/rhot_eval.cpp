// rhot-eval: measurements a user sizing a rig wants, as one JSON object on stdout.
//
//   rhot-eval triangulation --rig FILE [--sigma PX] [--frames N] [--seed S] [--markers M]
//                           [--dropout P] [--volume-m X Y Z] [--volume-centre-m X Y Z] --json
//   rhot-eval hands --rig FILE [--layout FILE] [--motion NAME|all] [--sigma PX] [--frames N] --json
//   rhot-eval stars --rig FILE --set FILE [--bodies N] [--sigma PX] [--frames N] [--seed S] [--dropout P] --json
//   rhot-eval wand --rig FILE [--length-mm 195] [--sigma PX] [--frames N] [--seed S] [--dropout P]
//                  [--volume-m X Y Z] [--volume-centre-m X Y Z] --json
//
// Markers wander through a box: the flags', else the rig file's tracking volume, else a 1 m cube
// where the cameras' optical axes meet (least squares); the simulated rig sees them with Gaussian noise and dropouts; matching and
// triangulation recover them; the result is compared with ground truth and with the Cramer-Rao
// bound of each point for the cameras that saw it.

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

#include "engine/app/FrameLoop.h"
#include "engine/demo/DemoRuntime.h"
#include "engine/physics/GraspScenarios.h"
#include "engine/scene/SceneLoader.h"
#include "tracking/camera/RigFile.h"
#include "tracking/geometry/Matching.h"
#include "tracking/hand/HandMotions.h"
#include "tracking/hand/HandTracker.h"
#include "tracking/rigid/StarTracker.h"
#include "tracking/source/SimulatedRig.h"

namespace {

// The point nearest (least squares) to every camera's optical axis.
Eigen::Vector3d axes_meeting_point(const rhot::CameraRig& rig) {
  Eigen::Matrix3d a = Eigen::Matrix3d::Zero();
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
  for (const rhot::Camera& c : rig.cameras) {
    const Eigen::Vector3d o = c.centre_world();
    const Eigen::Vector3d d = c.cam_from_world.rotation.conjugate() * Eigen::Vector3d::UnitZ();
    const Eigen::Matrix3d p = Eigen::Matrix3d::Identity() - d * d.transpose();
    a += p;
    b += p * o;
  }
  return a.ldlt().solve(b);
}

// A matched point further than this from every true marker is a ghost.
constexpr double kGhostDistance_m = 0.005;

// The box simulated markers move in: the flags when given, else the rig file's tracking volume,
// else a 1 m cube where the optical axes meet.
struct Box {
  Eigen::Vector3d centre;
  Eigen::Vector3d size;
};
Box evaluation_box(const rhot::CameraRig& rig, const std::vector<double>& size, const std::vector<double>& centre) {
  Box box{axes_meeting_point(rig), Eigen::Vector3d::Ones()};
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

int triangulation(const std::string& rig_file, double sigma, int frames, unsigned seed, int markers, double dropout,
                  const std::vector<double>& volume, const std::vector<double>& volume_centre) {
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
  rhot::SimulatedRig sim(*rig, rhot::random_trajectories(markers, centre - half, centre + half, seed + 1), settings);

  double sum_error2 = 0.0;
  double sum_bound2 = 0.0;
  long points = 0;
  long findable = 0;
  long found = 0;
  long ghosts = 0;
  long mixed = 0;
  std::vector<double> ms;
  for (int f = 0; f < frames; ++f) {
    const rhot::RigFrame frame = sim.next();
    const auto start = std::chrono::steady_clock::now();
    const auto matched = rhot::match_and_triangulate(*rig, frame);
    ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
    std::vector<int> seen_by(frame.truth_position_m.size(), 0);
    for (const rhot::CameraFrame& cf : frame.cameras) {
      for (const rhot::Detection& d : cf.detections) ++seen_by[static_cast<std::size_t>(d.truth_marker)];
    }
    for (const int n : seen_by) findable += n >= 2 ? 1 : 0;
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
      ++found;
      const Eigen::Vector3d truth = frame.truth_position_m[static_cast<std::size_t>(marker)];
      const auto cov = rhot::crlb_covariance(*rig, truth, m.point.cameras, sigma);
      if (!cov) continue;
      sum_error2 += (m.point.position_world - truth).squaredNorm();
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
  j["volume_centre_m"] = {centre.x(), centre.y(), centre.z()};
  j["volume_size_m"] = {box.size.x(), box.size.y(), box.size.z()};
  j["rms_mm"] = rms_mm;
  j["crlb_mm"] = crlb_mm;
  j["ratio"] = crlb_mm > 0.0 ? rms_mm / crlb_mm : 0.0;
  // Markers seen by two or more cameras, per frame: what there was to find.
  j["findable_per_frame"] = static_cast<double>(findable) / static_cast<double>(frames);
  j["found_fraction"] = findable > 0 ? static_cast<double>(found) / static_cast<double>(findable) : 0.0;
  j["ghosts"] = ghosts;
  j["mixed"] = mixed;
  j["median_ms"] = percentile(ms, 0.5);
  j["p99_ms"] = percentile(ms, 0.99);
  std::cout << j.dump(2) << "\n";
  return 0;
}

// A two-marker wand of known length waved through the volume; the measured length per frame
// against the true one (the Wiimote thesis's accuracy test).
int wand(const std::string& rig_file, double length_mm, double sigma, int frames, unsigned seed, double dropout,
         const std::vector<double>& volume, const std::vector<double>& volume_centre) {
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
  rhot::SimulatedRig sim(*rig, {ends[0], ends[1]}, settings);
  double sum_abs = 0.0;
  double sum_sq = 0.0;
  double max_abs = 0.0;
  long measured = 0;
  for (int f = 0; f < frames; ++f) {
    const rhot::RigFrame frame = sim.next();
    const auto matched = rhot::match_and_triangulate(*rig, frame);
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

}  // namespace

// Marker stars moving through the volume (25 of a set by default), matched, triangulated and
// tracked; identities against the truth, poses against the true poses.
int stars(const std::string& rig_file, const std::string& set_file, int bodies, double sigma, int frames, unsigned seed, double dropout,
          const std::vector<double>& volume, const std::vector<double>& volume_centre) {
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
  rhot::SimulatedRigSettings settings;
  settings.sigma_px = sigma;
  settings.dropout = dropout;
  settings.seed = seed;
  rhot::SimulatedRig sim(*rig, {}, settings);
  sim.set_bodies(simulated);
  // The tracker knows the stars in the scene, as a scene file tells it.
  rhot::StarSet in_use = *set;
  in_use.stars.resize(static_cast<std::size_t>(bodies));
  rhot::StarTracker tracker{rhot::StarLibrary(in_use)};

  long identifiable = 0;  // body-frames with three or more of the body's markers triangulated
  long correct = 0;       // ... among them, the body's star reported at the body's markers
  long wrong = 0;         // a star reported at another body's markers
  long posed = 0;
  double sum_position2 = 0.0;
  double sum_rotation2 = 0.0;
  std::vector<double> ms;
  for (int f = 0; f < frames; ++f) {
    const rhot::RigFrame frame = sim.next();
    const auto matched = rhot::match_and_triangulate(*rig, frame);
    std::vector<Eigen::Vector3d> points;
    std::vector<int> point_body;  // the body all of a point's detections belong to; -1: none, or several
    std::vector<int> clean(static_cast<std::size_t>(bodies), 0);
    for (const rhot::MatchedPoint& m : matched) {
      points.push_back(m.point.position_world);
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
      point_body.push_back(body);
      if (point_body.back() >= 0) ++clean[static_cast<std::size_t>(point_body.back())];
    }
    const auto start = std::chrono::steady_clock::now();
    const auto& tracked = tracker.update(frame.time_s, points);
    ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
    for (int b = 0; b < bodies; ++b) identifiable += clean[static_cast<std::size_t>(b)] >= 3 ? 1 : 0;
    for (const rhot::TrackedStar& t : tracked) {
      if (!t.seen_now()) continue;
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
      if (other || !own) {
        ++wrong;
        continue;
      }
      if (clean[static_cast<std::size_t>(t.star)] >= 3) ++correct;
      const rhot::Rigid3d& truth = frame.truth_world_from_body[static_cast<std::size_t>(t.star)];
      sum_position2 += (t.world_from_star.translation - truth.translation).squaredNorm();
      const double angle = Eigen::AngleAxisd(t.world_from_star.rotation * truth.rotation.conjugate()).angle();
      sum_rotation2 += angle * angle;
      ++posed;
    }
    if (frames >= 20 && (f + 1) % (frames / 10) == 0) std::cerr << "rhot-eval: frame " << f + 1 << " of " << frames << "\n";
  }
  nlohmann::json j;
  j["rig"] = rig_file;
  j["set"] = set_file;
  j["bodies"] = bodies;
  j["sigma_px"] = sigma;
  j["dropout"] = dropout;
  j["frames"] = frames;
  j["seed"] = seed;
  j["volume_centre_m"] = {box.centre.x(), box.centre.y(), box.centre.z()};
  j["volume_size_m"] = {box.size.x(), box.size.y(), box.size.z()};
  j["identifiable_body_frames"] = identifiable;
  j["correct_id_fraction"] = identifiable > 0 ? static_cast<double>(correct) / static_cast<double>(identifiable) : 0.0;
  j["wrong_id_count"] = wrong;
  j["posed_body_frames"] = posed;
  j["position_rms_mm"] = posed > 0 ? 1000.0 * std::sqrt(sum_position2 / static_cast<double>(posed)) : 0.0;
  j["rotation_rms_deg"] = posed > 0 ? std::sqrt(sum_rotation2 / static_cast<double>(posed)) * 180.0 / std::numbers::pi : 0.0;
  j["median_ms"] = percentile(ms, 0.5);
  j["p99_ms"] = percentile(ms, 0.99);
  std::cout << j.dump(2) << "\n";
  return 0;
}

// One or every scripted hand motion through the simulated rig with a hand layout: the hand's
// markers (its own bones hiding them) matched, triangulated, the hand star tracked, the fingers
// solved, and every joint compared with the truth.
nlohmann::json hand_motion_run(const rhot::CameraRig& rig, const rhot::HandLayout& layout, std::string_view motion, double sigma,
                               int frames, unsigned seed, const Eigen::Vector3d& centre, bool filter) {
  const rhot::HandPose skeleton = rhot::reference_open_hand(layout.side);
  const auto chains = rhot::hand_chains(skeleton, layout.side);
  const auto relaxed = rhot::HandSolver(layout.side, skeleton).state().angles;
  auto truth_at = [&](double t) {
    const auto frame = *rhot::hand_motion(motion, t, chains, relaxed, centre);
    return std::make_pair(frame.world_from_hand, rhot::hand_pose_from_angles(skeleton, chains, frame.angles));
  };
  auto markers_at = [&](double t) {
    const auto [world_from_hand, pose] = truth_at(t);
    return rhot::layout_markers(layout, world_from_hand, pose);
  };
  rhot::SimulatedRigSettings settings;
  settings.sigma_px = sigma;
  settings.seed = seed;
  rhot::SimulatedRig sim(rig, {}, settings);
  sim.set_scripted_markers(markers_at);
  rhot::HandTrackerSettings tracker_settings;
  tracker_settings.filter = filter;
  rhot::HandTracker tracker(layout, skeleton, tracker_settings);

  std::vector<double> tip_errors, joint_errors, ik_us, tracker_us;
  long joint_frames = 0, confident = 0, tip_frames = 0, tips_seen = 0, hand_frames = 0, segment_stars_seen = 0;
  for (int f = 0; f < frames; ++f) {
    const double t = static_cast<double>(f) / settings.rate_hz;
    // The hand's own bones hide its markers: capsules a little thinner than the joints' radii.
    const auto [world_from_hand, pose] = truth_at(t);
    std::vector<rhot::Occluder> bones;
    for (int j = 0; j < rhot::kHandJointCount; ++j) {
      const auto parent = rhot::joint_parent(static_cast<rhot::HandJoint>(j));
      if (!parent) continue;
      bones.push_back({world_from_hand * pose.position_m[static_cast<std::size_t>(*parent)],
                       world_from_hand * pose.position_m[static_cast<std::size_t>(j)], 0.8 * pose.radius_m[static_cast<std::size_t>(j)]});
    }
    sim.set_occluders(bones);
    const rhot::RigFrame frame = sim.next();
    std::vector<Eigen::Vector3d> points;
    for (const rhot::MatchedPoint& m : rhot::match_and_triangulate(rig, frame)) points.push_back(m.point.position_world);
    const auto tracker_start = std::chrono::steady_clock::now();
    const rhot::TrackedHand& hand = tracker.update(frame.time_s, points);
    tracker_us.push_back(std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - tracker_start).count());
    ik_us.push_back(tracker.last_ik_us());
    ++tip_frames;
    if (!hand.hand_seen) continue;
    ++hand_frames;
    segment_stars_seen += hand.segment_stars_seen;
    for (int j = 0; j < rhot::kHandJointCount; ++j) {
      const double e =
          (hand.joints_world[static_cast<std::size_t>(j)] - world_from_hand * pose.position_m[static_cast<std::size_t>(j)]).norm();
      joint_errors.push_back(1000.0 * e);
      ++joint_frames;
      confident += hand.state.confidence[static_cast<std::size_t>(j)] >= 0.5 ? 1 : 0;
    }
    for (int fi = 0; fi < rhot::kFingerCount; ++fi) {
      // A fingertip measured this frame: its marker found, or its distal bone's star seen.
      if (!hand.state.tip_seen[static_cast<std::size_t>(fi)]) continue;
      ++tips_seen;
      const auto tip = static_cast<std::size_t>(rhot::chain_joints(static_cast<rhot::Finger>(fi))[3]);
      tip_errors.push_back(1000.0 * (hand.joints_world[tip] - world_from_hand * pose.position_m[tip]).norm());
    }
  }
  auto mean = [](const std::vector<double>& v) {
    double s = 0.0;
    for (const double x : v) s += x;
    return v.empty() ? 0.0 : s / static_cast<double>(v.size());
  };
  nlohmann::json j;
  j["frames"] = frames;
  j["hand_seen_fraction"] = static_cast<double>(hand_frames) / static_cast<double>(std::max(1L, tip_frames));
  j["fingertips_seen_fraction"] = static_cast<double>(tips_seen) / static_cast<double>(std::max(1L, 5 * hand_frames));
  if (!layout.segment_stars.empty()) {
    j["segment_stars_seen_fraction"] = static_cast<double>(segment_stars_seen) /
                                       static_cast<double>(std::max(1L, hand_frames * static_cast<long>(layout.segment_stars.size())));
  }
  j["fingertip_mean_mm"] = mean(tip_errors);
  j["fingertip_p95_mm"] = percentile(tip_errors, 0.95);
  j["joint_mean_mm"] = mean(joint_errors);
  j["joint_p95_mm"] = percentile(joint_errors, 0.95);
  j["joints_with_confidence_fraction"] = static_cast<double>(confident) / static_cast<double>(std::max(1L, joint_frames));
  j["ik_median_us"] = percentile(ik_us, 0.5);
  j["ik_p99_us"] = percentile(ik_us, 0.99);
  j["tracker_median_us"] = percentile(tracker_us, 0.5);
  j["tracker_p99_us"] = percentile(tracker_us, 0.99);
  return j;
}

int hands(const std::string& rig_file, const std::string& layout_file, const std::string& motion, double sigma, int frames, unsigned seed,
          const std::vector<double>& volume_centre, bool filter) {
  const auto rig = rhot::load_rig(rig_file);
  if (!rig) {
    std::cerr << "rhot-eval: " << rig.error() << "\n";
    return 1;
  }
  const auto layout = rhot::load_hand_layout(layout_file);
  if (!layout) {
    std::cerr << "rhot-eval: " << layout.error() << "\n";
    return 1;
  }
  std::vector<std::string_view> motions;
  for (const std::string_view name : rhot::hand_motion_names()) {
    if (motion == "all" || motion == name) motions.push_back(name);
  }
  if (motions.empty()) {
    std::string known;
    for (const std::string_view name : rhot::hand_motion_names()) known += std::string(known.empty() ? "" : ", ") + std::string(name);
    std::cerr << "rhot-eval: --motion " << motion << ": no such motion (" << known << ", all)\n";
    return 1;
  }
  const Box box = evaluation_box(*rig, {}, volume_centre);
  nlohmann::json j;
  j["rig"] = rig_file;
  j["layout"] = layout_file;
  j["sigma_px"] = sigma;
  j["seed"] = seed;
  j["centre_m"] = {box.centre.x(), box.centre.y(), box.centre.z()};
  j["filter"] = filter;
  for (const std::string_view name : motions) {
    std::cerr << "rhot-eval: hand motion " << name << "\n";
    j["motions"][std::string(name)] = hand_motion_run(*rig, *layout, name, sigma, frames, seed, box.centre, filter);
  }
  // Over all motions: the mean of the motions' numbers (each motion weighs alike).
  for (const char* key :
       {"fingertip_mean_mm", "fingertip_p95_mm", "joint_mean_mm", "joint_p95_mm", "joints_with_confidence_fraction", "ik_median_us",
        "ik_p99_us", "tracker_median_us", "tracker_p99_us", "hand_seen_fraction", "fingertips_seen_fraction"}) {
    double sum = 0.0;
    for (const auto& [name, m] : j["motions"].items()) sum += m[key].get<double>();
    j[key] = sum / static_cast<double>(motions.size());
  }
  std::cout << j.dump(2) << "\n";
  return 0;
}

// Scripted grasp scenarios through the real physics (engine/physics/GraspScenarios.h).
int grasp(const std::string& scenario) {
  std::vector<std::string_view> names;
  for (const std::string_view n : rhot::grasp_scenario_names()) {
    if (scenario == "all" || scenario == n) names.push_back(n);
  }
  if (names.empty()) {
    std::string list;
    for (const std::string_view n : rhot::grasp_scenario_names()) list += std::string(n) + ", ";
    std::cerr << "rhot-eval: --scenario " << scenario << ": no such scenario (" << list << "all)\n";
    return 1;
  }
  nlohmann::json j;
  std::vector<double> steps;
  int lifts = 0, lifted = 0;
  double max_slip = 0.0;
  std::optional<double> throw_error;
  for (const std::string_view name : names) {
    std::cerr << "rhot-eval: grasp scenario " << name << "\n";
    const auto r = rhot::run_grasp_scenario(name);
    if (!r) {
      std::cerr << "rhot-eval: " << r.error() << "\n";
      return 1;
    }
    nlohmann::json s;
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
      if (e.hand) ev["hand"] = *e.hand == rhot::HandSide::kLeft ? "left" : "right";
      if (!e.interaction.empty()) ev["interaction"] = e.interaction;
      events.push_back(ev);
    }
    s["events"] = events;
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
  j["max_slip_mm"] = max_slip;
  if (throw_error) j["throw_velocity_error_pct"] = *throw_error;
  j["step_p50_ms"] = percentile(steps, 0.5);
  j["step_p99_ms"] = percentile(steps, 0.99);
  std::cout << j.dump(2) << "\n";
  return 0;
}

// The demo's whole frame, headless: simulated cameras, tracking, physics and both eyes rendered
// offscreen, every stage timed (engine/demo/DemoRuntime.h).
int frame(const std::string& scene_file, const std::string& eye, int frames, const std::string& device, rhot::Shading shading) {
  // stdout carries the JSON only: the log goes to stderr.
  spdlog::set_default_logger(spdlog::stderr_color_mt("rhot-eval"));
  const auto scene = rhot::load_scene_file(scene_file);
  if (!scene) {
    std::cerr << "rhot-eval: " << scene.error().to_string() << "\n";
    return 1;
  }
  rhot::RendererSettings render;
  render.eye_width_px = scene->settings.headset.eye_width_px;
  render.eye_height_px = scene->settings.headset.eye_height_px;
  render.device = device;
  render.shading = shading;
  if (!eye.empty()) {
    char x = 0, rest = 0;
    if (std::sscanf(eye.c_str(), "%d%c%d%c", &render.eye_width_px, &x, &render.eye_height_px, &rest) != 3 || (x != 'x' && x != 'X') ||
        render.eye_width_px < 16 || render.eye_height_px < 16 || render.eye_width_px > 8192 || render.eye_height_px > 8192) {
      std::cerr << "rhot-eval: --eye: expected WIDTHxHEIGHT, each 16 to 8192 pixels, such as 1080x1200, got \"" << eye << "\"\n";
      return 1;
    }
  }
  auto renderer = rhot::Renderer::create(render);
  if (!renderer) {
    std::cerr << "rhot-eval: cannot start the renderer: " << renderer.error() << "\n";
    return 1;
  }
  rhot::DemoOptions options;
  options.pipeline.asset_dir = RHOT_ASSET_DIR;
  auto runtime = rhot::DemoRuntime::create(*scene, renderer->get(), options);
  if (!runtime) {
    std::cerr << "rhot-eval: " << runtime.error() << "\n";
    return 1;
  }
  rhot::Systems systems;
  (*runtime)->add_systems(systems, "");
  if (const auto built = systems.build(); !built) {
    std::cerr << "rhot-eval: " << built.error() << "\n";
    return 1;
  }
  rhot::FrameLoopSettings loop;
  loop.rate_hz = scene->settings.headset.refresh_hz;
  loop.budget_ms = 1000.0 / loop.rate_hz;
  rhot::FrameLoop frame_loop((*runtime)->world(), systems, loop);
  for (int f = 0; f < frames; ++f) {
    frame_loop.step();
    if ((f + 1) % 90 == 0) std::cerr << "rhot-eval: frame " << (f + 1) << " of " << frames << "\n";
  }
  nlohmann::json j = frame_loop.stats().to_json();
  j["scene"] = scene_file;
  j["eye_px"] = {(*renderer)->eye_width_px(), (*renderer)->eye_height_px()};
  j["device"] = (*renderer)->info().device_name;
  j["cpu_device"] = (*renderer)->info().cpu_device;
  j["stereo"] = (*renderer)->info().mode == rhot::StereoMode::kMultiview ? "multiview" : "two-pass";
  j["shading"] = rhot::to_string((*renderer)->info().shading);
  std::cout << j.dump(2) << "\n";
  return 0;
}

int main(int argc, char** argv) {
  CLI::App app{"rhot-eval: accuracy and speed of rhot's tracking on simulated data, as JSON"};
  app.require_subcommand(1);
  auto* tri = app.add_subcommand("triangulation", "matching and triangulation accuracy against the Cramer-Rao bound");
  std::string rig_file;
  double sigma = 0.3;
  int frames = 100;
  unsigned seed = 1;
  int markers = 100;
  double dropout = 0.0;
  std::vector<double> volume;
  std::vector<double> volume_centre;
  bool json = false;
  tri->add_option("--rig", rig_file, "camera rig (OpenCV YAML)")->required();
  tri->add_option("--sigma", sigma, "pixel noise, standard deviation per axis")->capture_default_str()->check(CLI::Range(1e-6, 50.0));
  tri->add_option("--frames", frames, "frames to simulate")->capture_default_str()->check(CLI::Range(1, 1000000));
  tri->add_option("--seed", seed, "random seed")->capture_default_str();
  tri->add_option("--markers", markers, "markers in the volume")->capture_default_str()->check(CLI::Range(1, 10000));
  tri->add_option("--dropout", dropout, "probability a camera misses a visible marker")->capture_default_str()->check(CLI::Range(0.0, 1.0));
  const char* volume_help = "size of the box the markers move in, X Y Z metres (default: the rig file's volume_size, else 1 1 1)";
  const char* centre_help = "centre of that box, X Y Z metres (default: the rig file's volume_centre, else where the optical axes meet)";
  tri->add_option("--volume-m", volume, volume_help)->expected(3)->check(CLI::PositiveNumber);
  tri->add_option("--volume-centre-m", volume_centre, centre_help)->expected(3);
  tri->add_flag("--json", json, "print JSON (the only output format)");
  auto* wand_cmd = app.add_subcommand("wand", "length of a two-marker wand waved through the volume (mean and RMS error)");
  double length_mm = 195.0;
  wand_cmd->add_option("--rig", rig_file, "camera rig (OpenCV YAML)")->required();
  wand_cmd->add_option("--length-mm", length_mm, "true wand length")->capture_default_str()->check(CLI::Range(1.0, 5000.0));
  wand_cmd->add_option("--sigma", sigma, "pixel noise, standard deviation per axis")->capture_default_str()->check(CLI::Range(1e-6, 50.0));
  wand_cmd->add_option("--frames", frames, "frames to simulate")->capture_default_str()->check(CLI::Range(1, 1000000));
  wand_cmd->add_option("--seed", seed, "random seed")->capture_default_str();
  wand_cmd->add_option("--dropout", dropout, "probability a camera misses a visible marker")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
  wand_cmd->add_option("--volume-m", volume, volume_help)->expected(3)->check(CLI::PositiveNumber);
  wand_cmd->add_option("--volume-centre-m", volume_centre, centre_help)->expected(3);
  wand_cmd->add_flag("--json", json, "print JSON (the only output format)");
  auto* stars_cmd = app.add_subcommand("stars", "marker stars moving through the volume: identification and pose against the truth");
  std::string set_file;
  int bodies = 25;
  stars_cmd->add_option("--rig", rig_file, "camera rig (OpenCV YAML)")->required();
  stars_cmd->add_option("--set", set_file, "marker star set (JSON, from rhot-stars)")->required();
  stars_cmd->add_option("--bodies", bodies, "stars moving at once (the set's first ones)")
      ->capture_default_str()
      ->check(CLI::Range(1, 10000));
  stars_cmd->add_option("--sigma", sigma, "pixel noise, standard deviation per axis")->capture_default_str()->check(CLI::Range(1e-6, 50.0));
  stars_cmd->add_option("--frames", frames, "frames to simulate")->capture_default_str()->check(CLI::Range(1, 1000000));
  stars_cmd->add_option("--seed", seed, "random seed")->capture_default_str();
  stars_cmd->add_option("--dropout", dropout, "probability a camera misses a visible marker")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
  stars_cmd->add_option("--volume-m", volume, volume_help)->expected(3)->check(CLI::PositiveNumber);
  stars_cmd->add_option("--volume-centre-m", volume_centre, centre_help)->expected(3);
  stars_cmd->add_flag("--json", json, "print JSON (the only output format)");
  auto* hands_cmd = app.add_subcommand("hands", "scripted hand motions with a hand layout: every joint against the truth");
  std::string layout_file = std::string(RHOT_ASSET_DIR) + "/hands/low-cost-right.json";
  std::string motion = "all";
  int hand_frames = 450;
  hands_cmd->add_option("--rig", rig_file, "camera rig (OpenCV YAML)")->required();
  hands_cmd->add_option("--layout", layout_file, "hand marker layout (JSON)")->capture_default_str();
  hands_cmd->add_option("--motion", motion, "open, fist, pinch, wave, power-grasp, precision-grasp or all")->capture_default_str();
  hands_cmd->add_option("--sigma", sigma, "pixel noise, standard deviation per axis")->capture_default_str()->check(CLI::Range(1e-6, 50.0));
  hands_cmd->add_option("--frames", hand_frames, "frames per motion")->capture_default_str()->check(CLI::Range(1, 1000000));
  hands_cmd->add_option("--seed", seed, "random seed")->capture_default_str();
  hands_cmd->add_option("--volume-centre-m", volume_centre, "where the hand moves, X Y Z metres (default: the rig's volume centre)")
      ->expected(3);
  bool filter = false;
  hands_cmd->add_flag("--filter", filter, "1-euro filter the hand frame and the fingertips before the IK");
  hands_cmd->add_flag("--json", json, "print JSON (the only output format)");
  auto* grasp_cmd =
      app.add_subcommand("grasp", "scripted grasps through the physics: lift, pinch, throw, push, hand-over, hidden markers, place");
  std::string scenario = "all";
  grasp_cmd->add_option("--scenario", scenario, "a scenario name or all")->capture_default_str();
  grasp_cmd->add_flag("--json", json, "print JSON (the only output format)");
  auto* frame_cmd = app.add_subcommand(
      "frame", "the demo's whole frame headless (cameras, tracking, physics, both eyes): p50, p99, budget misses, per stage");
  std::string scene_file = std::string(RHOT_ASSET_DIR) + "/scenes/default.json";
  std::string eye;
  int frame_count = 900;
  std::string device = "auto";
  frame_cmd->add_option("--scene", scene_file, "scene file (JSON)")->capture_default_str();
  frame_cmd->add_option("--eye", eye, "pixels per eye, WxH (default: the scene's headset, 1080x1200)");
  frame_cmd->add_option("--frames", frame_count, "frames to run")->capture_default_str()->check(CLI::Range(1, 1000000));
  frame_cmd->add_option("--device", device, "Vulkan device: auto, gpu, cpu, an index or part of its name")->capture_default_str();
  std::string shading = "auto";
  frame_cmd->add_option("--shading", shading, "light per pixel, per vertex, or auto (per vertex on a CPU driver)")
      ->capture_default_str()
      ->check(CLI::IsMember({"auto", "pixel", "vertex"}));
  frame_cmd->add_flag("--json", json, "print JSON (the only output format)");
  CLI11_PARSE(app, argc, argv);
  if (grasp_cmd->parsed()) return grasp(scenario);
  if (frame_cmd->parsed()) return frame(scene_file, eye, frame_count, device, *rhot::shading_from_string(shading));
  if (tri->parsed()) return triangulation(rig_file, sigma, frames, seed, markers, dropout, volume, volume_centre);
  if (hands_cmd->parsed()) return hands(rig_file, layout_file, motion, sigma, hand_frames, seed, volume_centre, filter);
  if (stars_cmd->parsed()) return stars(rig_file, set_file, bodies, sigma, frames, seed, dropout, volume, volume_centre);
  if (wand_cmd->parsed()) return wand(rig_file, length_mm, sigma, frames, seed, dropout, volume, volume_centre);
  return 1;
}
