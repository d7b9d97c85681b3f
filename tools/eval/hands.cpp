// rhot-eval hands: scripted hand motions through the simulated rig with a hand layout, every joint
// against the truth.

#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <limits>
#include <numbers>
#include <numeric>
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
#include "tracking/hand/HandCalibration.h"
#include "tracking/hand/HandTracker.h"
#include "tracking/rigid/StarTracker.h"
#include "tracking/sim/SimulatedRig.h"

#include "tools/eval/Eval.h"

namespace rhot::eval {

namespace {

// The user's calibration (HandCalibration.h): the truth hand held flat (every finger straight) for
// a second where `motion` starts, through its own simulated rig, tracked with the reference
// skeleton (its frame filtered as the tracker's will be); the fingertip markers found give each
// finger's length. None when no fingertip was found.
std::optional<rhot::HandPose> calibrated_skeleton(const rhot::CameraRig& rig, const rhot::CameraRig& tracker_rig,
                                                  const rhot::HandLayout& layout, const rhot::HandPose& reference,
                                                  const rhot::HandPose& user, const rhot::Rigid3d& world_from_hand,
                                                  rhot::SimulatedRigSettings settings, bool filter_frame, rhot::JobPool& jobs) {
  const auto flat = rhot::hand_pose_from_angles(user, rhot::hand_chains(user, layout.side), {});
  settings.seed += 1000;  // not the motion's noise
  rhot::SimulatedRig sim(rig, {}, settings);
  const auto markers = rhot::layout_markers(layout, world_from_hand, flat);
  sim.set_scripted_markers([&](double) { return markers; });
  rhot::HandTrackerSettings tracker_settings;
  tracker_settings.filter_frame = filter_frame;
  rhot::HandTracker tracker(layout, reference, tracker_settings);
  rhot::PixelSigmaEstimate pixel_sigma;
  std::vector<rhot::FingertipSample> samples;
  const rhot::RigMatcher matcher(tracker_rig);
  for (int f = 0; f < static_cast<int>(settings.rate_hz); ++f) {
    const rhot::RigFrame frame = sim.next();
    const auto matched = matcher.match(frame, rhot::match_settings_for(pixel_sigma.sigma_px()), &jobs);
    std::vector<Eigen::Vector3d> points;
    for (const rhot::MatchedPoint& m : matched) points.push_back(m.point.position_world);
    const rhot::TrackedHand& hand = tracker.update(frame.time_s, points, rhot::point_sigmas_m(matched, pixel_sigma.update(matched)));
    samples.push_back(rhot::flat_hand_sample(layout, reference, hand, points));
  }
  return rhot::calibrate_flat_hand(reference, layout.side, samples);
}

// One or every scripted hand motion through the simulated rig with a hand layout: the hand's
// markers (its own bones hiding them) matched, triangulated, the hand star tracked, the fingers
// solved, and every joint compared with the truth.
nlohmann::json hand_motion_run(const rhot::CameraRig& rig, const rhot::HandLayout& layout, std::string_view motion,
                               const rhot::WorldSettings& world, const HandsArgs& args, const Eigen::Vector3d& centre,
                               std::vector<double>& hidden_tip_errors, rhot::JobPool& jobs) {
  const unsigned seed = args.seed;
  const int frames = args.frames;
  const rhot::HandPose skeleton = rhot::reference_open_hand(layout.side);
  const auto chains = rhot::hand_chains(skeleton, layout.side);
  const auto relaxed = rhot::HandSolver(layout.side, skeleton).state().angles;
  // The user's own hand: the model's, or one with its own bones and angles.
  const rhot::HandPose user = world.independent_hands ? rhot::independent_hand(skeleton, seed) : skeleton;
  const auto user_chains = rhot::hand_chains(user, layout.side);
  auto truth_at = [&](double t) {
    const auto frame = *rhot::hand_motion(motion, t, chains, relaxed, centre);
    const auto angles = world.independent_hands ? rhot::independent_angles(frame.angles, seed) : frame.angles;
    return std::make_pair(frame.world_from_hand, rhot::hand_pose_from_angles(user, user_chains, angles));
  };
  auto markers_at = [&](double t) {
    const auto [world_from_hand, pose] = truth_at(t);
    return rhot::layout_markers(layout, world_from_hand, pose);
  };
  rhot::SimulatedRigSettings settings = world.rig_settings(seed);
  rhot::SimulatedRig sim(rig, {}, settings);
  sim.set_scripted_markers(markers_at);
  // The tracker's rig: the truth, or as an imperfect calibration has it.
  const rhot::CameraRig tracker_rig = rhot::perturbed_rig(rig, world.calib_error_px, seed);
  rhot::PixelSigmaEstimate pixel_sigma;
  rhot::HandTrackerSettings tracker_settings;
  tracker_settings.filter = args.filter;
  tracker_settings.filter_frame = args.filter_frame;
  tracker_settings.fingertip_model = args.fingertip_model;
  const std::optional<rhot::HandPose> calibrated =
      args.calibrate_hand
          ? calibrated_skeleton(rig, tracker_rig, layout, skeleton, user, truth_at(0.0).first, settings, args.filter_frame, jobs)
          : std::nullopt;
  if (calibrated) tracker_settings.finger_length_tolerance = 0.0;  // the skeleton is the user's
  const rhot::HandPose tracked_skeleton = calibrated.value_or(skeleton);
  rhot::HandTracker tracker(layout, tracked_skeleton, tracker_settings);

  std::vector<double> tip_errors, hidden_errors, joint_errors, ik_us, tracker_us;
  long joint_frames = 0, confident = 0, tip_frames = 0, tips_seen = 0, hand_frames = 0, segment_stars_seen = 0, reported_wrong = 0;
  const rhot::RigMatcher matcher(tracker_rig);
  for (int f = 0; f < frames; ++f) {
    const double t = static_cast<double>(f) / settings.rate_hz;
    // The hand's own bones hide its markers.
    const auto [world_from_hand, pose] = truth_at(t);
    const std::vector<rhot::Occluder> bones = rhot::hand_bone_occluders(world_from_hand, pose);
    sim.set_occluders(bones);
    const rhot::RigFrame frame = sim.next();
    std::vector<Eigen::Vector3d> points;
    const auto matched = matcher.match(frame, rhot::match_settings_for(pixel_sigma.sigma_px()), &jobs);
    for (const rhot::MatchedPoint& m : matched) points.push_back(m.point.position_world);
    const auto tracker_start = std::chrono::steady_clock::now();
    const rhot::TrackedHand& hand = tracker.update(frame.time_s, points, rhot::point_sigmas_m(matched, pixel_sigma.update(matched)));
    tracker_us.push_back(std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - tracker_start).count());
    ik_us.push_back(tracker.last_ik_us());
    ++tip_frames;
    if (!hand.hand_seen) continue;
    ++hand_frames;
    // Reported as seen, but not where the hand is: the wrist 10 mm or the hand 5 degrees off.
    const double hand_turn = Eigen::AngleAxisd(hand.world_from_hand.rotation * world_from_hand.rotation.conjugate()).angle();
    const auto wrist = static_cast<std::size_t>(rhot::HandJoint::kWrist);
    if ((hand.joints_world[wrist] - world_from_hand * pose.position_m[wrist]).norm() > 0.010 || hand_turn > 5.0 * std::numbers::pi / 180.0)
      ++reported_wrong;
    segment_stars_seen += hand.segment_stars_seen;
    for (int j = 0; j < rhot::kHandJointCount; ++j) {
      const double e =
          (hand.joints_world[static_cast<std::size_t>(j)] - world_from_hand * pose.position_m[static_cast<std::size_t>(j)]).norm();
      joint_errors.push_back(1000.0 * e);
      ++joint_frames;
      confident += hand.state.confidence[static_cast<std::size_t>(j)] >= 0.5 ? 1 : 0;
    }
    for (int fi = 0; fi < rhot::kFingerCount; ++fi) {
      // A fingertip measured this frame (its marker found, or its distal bone's star seen), or
      // estimated while hidden.
      const auto tip = static_cast<std::size_t>(rhot::chain_joints(static_cast<rhot::Finger>(fi))[3]);
      const double e = 1000.0 * (hand.joints_world[tip] - world_from_hand * pose.position_m[tip]).norm();
      if (!hand.state.tip_seen[static_cast<std::size_t>(fi)]) {
        hidden_errors.push_back(e);
        continue;
      }
      ++tips_seen;
      tip_errors.push_back(e);
    }
  }
  auto mean = [](const std::vector<double>& v) {
    double s = 0.0;
    for (const double x : v) s += x;
    return v.empty() ? 0.0 : s / static_cast<double>(v.size());
  };
  nlohmann::json j;
  j["frames"] = frames;
  j["reported_wrong_fraction"] = static_cast<double>(reported_wrong) / static_cast<double>(std::max(1L, hand_frames));
  j["hand_seen_fraction"] = static_cast<double>(hand_frames) / static_cast<double>(std::max(1L, tip_frames));
  j["fingertips_seen_fraction"] = static_cast<double>(tips_seen) / static_cast<double>(std::max(1L, 5 * hand_frames));
  if (!layout.segment_stars.empty()) {
    j["segment_stars_seen_fraction"] = static_cast<double>(segment_stars_seen) /
                                       static_cast<double>(std::max(1L, hand_frames * static_cast<long>(layout.segment_stars.size())));
  }
  j["fingertip_mean_mm"] = mean(tip_errors);
  j["fingertip_p95_mm"] = percentile(tip_errors, 0.95);
  j["hidden_tip_mean_mm"] = mean(hidden_errors);
  j["hidden_tip_p95_mm"] = percentile(hidden_errors, 0.95);
  j["hidden_tip_frames"] = hidden_errors.size();
  hidden_tip_errors.insert(hidden_tip_errors.end(), hidden_errors.begin(), hidden_errors.end());
  j["joint_mean_mm"] = mean(joint_errors);
  j["joint_p95_mm"] = percentile(joint_errors, 0.95);
  j["joints_with_confidence_fraction"] = static_cast<double>(confident) / static_cast<double>(std::max(1L, joint_frames));
  j["ik_median_us"] = percentile(ik_us, 0.5);
  j["ik_p99_us"] = percentile(ik_us, 0.99);
  j["tracker_median_us"] = percentile(tracker_us, 0.5);
  j["tracker_p99_us"] = percentile(tracker_us, 0.99);
  return j;
}

}  // namespace

int hands(const HandsArgs& args) {
  if (!args.take_file.empty()) return hands_take(args);
  if (args.rig_file.empty()) {
    std::cerr << "rhot-eval: hands needs --rig (simulated hands through a rig) or --take (a recorded take)\n";
    return 1;
  }
  const auto world = world_settings(args.world);
  if (!world) {
    std::cerr << "rhot-eval: " << world.error() << "\n";
    return 1;
  }
  const auto rig = rhot::load_rig(args.rig_file);
  if (!rig) {
    std::cerr << "rhot-eval: " << rig.error() << "\n";
    return 1;
  }
  const auto layout = rhot::load_hand_layout(args.layout_file);
  if (!layout) {
    std::cerr << "rhot-eval: " << layout.error() << "\n";
    return 1;
  }
  std::vector<std::string_view> motions;
  for (const std::string_view name : rhot::hand_motion_names()) {
    if (args.motion == "all" || args.motion == name) motions.push_back(name);
  }
  if (motions.empty()) {
    std::string known;
    for (const std::string_view name : rhot::hand_motion_names()) known += std::string(known.empty() ? "" : ", ") + std::string(name);
    std::cerr << "rhot-eval: --motion " << args.motion << ": no such motion (" << known << ", all)\n";
    return 1;
  }
  const Box box = evaluation_box(*rig, {}, args.volume_centre);
  nlohmann::json j;
  j["rig"] = args.rig_file;
  j["layout"] = args.layout_file;
  j["world"] = world_json(*world, args.world.world);
  j["seed"] = args.seed;
  j["centre_m"] = {box.centre.x(), box.centre.y(), box.centre.z()};
  j["filter"] = args.filter;
  j["filter_frame"] = args.filter_frame;
  j["calibrate_hand"] = args.calibrate_hand;
  j["fingertip_model"] = args.fingertip_model;
  rhot::JobPool jobs(rhot::threads_or_all(args.threads));
  j["threads"] = jobs.threads();
  std::vector<double> hidden_tip_errors;
  for (const std::string_view name : motions) {
    std::cerr << "rhot-eval: hand motion " << name << "\n";
    j["motions"][std::string(name)] = hand_motion_run(*rig, *layout, name, *world, args, box.centre, hidden_tip_errors, jobs);
  }
  // Hidden tips over every motion's hidden frames together (a motion may hide none).
  j["hidden_tip_mean_mm"] = hidden_tip_errors.empty() ? 0.0
                                                      : std::accumulate(hidden_tip_errors.begin(), hidden_tip_errors.end(), 0.0) /
                                                            static_cast<double>(hidden_tip_errors.size());
  j["hidden_tip_p95_mm"] = percentile(hidden_tip_errors, 0.95);
  j["hidden_tip_frames"] = hidden_tip_errors.size();
  // Over all motions: the mean of the motions' numbers (each motion weighs alike).
  for (const char* key :
       {"fingertip_mean_mm", "fingertip_p95_mm", "joint_mean_mm", "joint_p95_mm", "joints_with_confidence_fraction", "ik_median_us",
        "ik_p99_us", "tracker_median_us", "tracker_p99_us", "hand_seen_fraction", "fingertips_seen_fraction", "reported_wrong_fraction"}) {
    double sum = 0.0;
    for (const auto& [name, m] : j["motions"].items()) sum += m[key].get<double>();
    j[key] = sum / static_cast<double>(motions.size());
  }
  std::cout << j.dump(2) << "\n";
  return 0;
}

}  // namespace rhot::eval
