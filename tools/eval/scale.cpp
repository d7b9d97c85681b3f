// rhot-eval scale: a crowded stage run at the cameras' rate. People walk through the rig's volume,
// each with two tracked hands (a distinct marker star on the back of each, a marker on every
// fingertip) and props (rigid marker stars worn on the head and the back), among
// loose markers (suits, scenery) up to --markers in all. Every frame is matched, its stars followed
// and its hands solved on --threads threads; each stage is timed, and the bodies and hands are
// judged against the truth. The same run on one thread gives the speed-up and must give the same
// results (docs/tracking.md "Threads").

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <expected>
#include <fstream>
#include <iostream>
#include <numbers>
#include <optional>
#include <random>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>
#include <unistd.h>

#include "base/Jobs.h"
#include "tracking/camera/RigFile.h"
#include "tracking/geometry/Matching.h"
#include "tracking/hand/HandLayout.h"
#include "tracking/hand/HandTracker.h"
#include "tracking/rigid/StarSet.h"
#include "tracking/rigid/StarTracker.h"
#include "tracking/sim/HandMotions.h"
#include "tracking/sim/SimulatedRig.h"

#include "tools/eval/AllocationCount.h"
#include "tools/eval/Eval.h"

namespace rhot::eval {

namespace {

constexpr std::size_t kHandMarkers = 9;    // four on the back, one on each fingertip
constexpr double kBodyCorrect_m = 0.010;   // a body's reported origin within this of the truth
constexpr double kWristCorrect_m = 0.010;  // a hand seen with its wrist within this of the truth
constexpr double kTipCorrect_m = 0.020;    // a correct hand's fingertips, every one within this
constexpr double kWarmUp_s = 0.5;          // the trackers' first frames are not judged nor timed

// A person walking: a slow path over the floor, facing a heading that swings.
struct Walker {
  Eigen::Vector2d centre{0, 0}, amplitude{0, 0}, frequency_hz{0, 0}, phase{0, 0};
  double heading = 0.0, swing = 0.0, swing_hz = 0.0;
  Rigid3d world_from_person(double t) const {
    const double tau = 2.0 * std::numbers::pi * t;
    const Eigen::Vector3d at(centre.x() + amplitude.x() * std::sin(tau * frequency_hz.x() + phase.x()), 0.0,
                             centre.y() + amplitude.y() * std::sin(tau * frequency_hz.y() + phase.y()));
    const double yaw = heading + swing * std::sin(tau * swing_hz);
    return {Eigen::Quaterniond(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitY())), at};
  }
};

// Walking pace: paths of 0.5 to 2 m either way at 0.05 to 0.15 Hz (at most about 1.9 m/s).
std::vector<Walker> walkers(int count, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<Walker> out;
  for (int p = 0; p < count; ++p) {
    Walker w;
    for (int a = 0; a < 2; ++a) {
      const int axis = a == 0 ? 0 : 2;
      const double size = hi(axis) - lo(axis) - 1.0;  // half a metre clear of the volume's edges
      const double amplitude = std::min(0.5 + 1.5 * unit(rng), 0.25 * size);
      const double where = unit(rng);
      w.amplitude(a) = amplitude;
      w.centre(a) = lo(axis) + 0.5 + amplitude + (size - 2.0 * amplitude) * where;
      w.frequency_hz(a) = 0.05 + 0.1 * unit(rng);
      w.phase(a) = 2.0 * std::numbers::pi * unit(rng);
    }
    w.heading = 2.0 * std::numbers::pi * unit(rng);
    w.swing = 0.6 * unit(rng);
    w.swing_hz = 0.1 + 0.2 * unit(rng);
    out.push_back(w);
  }
  return out;
}

// A hand of the crowd: its layout (the low-cost one, its back's star replaced by one of the set's,
// so no two hands share a star), its skeleton, and the motion its fingers follow.
struct CrowdHand {
  HandLayout layout;
  HandPose skeleton;
  std::array<FingerChain, kFingerCount> chains{};
  std::array<FingerAngles, kFingerCount> relaxed{};
  std::string_view motion;
  int person = 0;
  Eigen::Vector3d person_from_hand_m{0, 0, 0};
};

struct Truth {
  std::vector<Rigid3d> world_from_hand;
  std::vector<HandPose> hand_pose;
  std::vector<Rigid3d> world_from_body;
};

// The crowd, set up once: who walks where, which hand and prop is whose.
struct Crowd {
  std::vector<Walker> people;
  std::vector<CrowdHand> hands;
  std::vector<std::array<Eigen::Vector3d, 4>> body_markers_m;  // per prop, in its frame
  std::vector<int> body_person;
  std::vector<double> body_turn_hz;

  Truth truth_at(double t) const {
    Truth out;
    for (const CrowdHand& h : hands) {
      const HandMotionFrame frame = *hand_motion(h.motion, t, h.chains, h.relaxed, Eigen::Vector3d::Zero());
      const Rigid3d person = people[static_cast<std::size_t>(h.person)].world_from_person(t);
      out.world_from_hand.push_back(person * Rigid3d(Eigen::Quaterniond::Identity(), h.person_from_hand_m) * frame.world_from_hand);
      out.hand_pose.push_back(hand_pose_from_angles(h.skeleton, h.chains, frame.angles));
    }
    for (std::size_t b = 0; b < body_markers_m.size(); ++b) {
      const Rigid3d person = people[static_cast<std::size_t>(body_person[b])].world_from_person(t);
      const double turn = 0.8 * std::sin(2.0 * std::numbers::pi * body_turn_hz[b] * t);
      // Worn clear of the hands: a person's first prop on the head (a headset), the second on the
      // back (there are at most two a person: --bodies sets how many people there are too).
      const Eigen::Vector3d held = b < people.size() ? Eigen::Vector3d(0.0, 1.7, 0.05) : Eigen::Vector3d(0.0, 1.35, -0.18);
      const Eigen::Quaterniond spin(Eigen::AngleAxisd(turn, Eigen::Vector3d(0.3, 1.0, 0.2).normalized()));
      out.world_from_body.push_back(person * Rigid3d(spin, held));
    }
    return out;
  }

  std::vector<Eigen::Vector3d> markers(const Truth& truth) const {
    std::vector<Eigen::Vector3d> out;
    for (std::size_t h = 0; h < hands.size(); ++h) {
      for (const Eigen::Vector3d& m : layout_markers(hands[h].layout, truth.world_from_hand[h], truth.hand_pose[h])) out.push_back(m);
    }
    for (std::size_t b = 0; b < body_markers_m.size(); ++b) {
      for (const Eigen::Vector3d& m : body_markers_m[b]) out.push_back(truth.world_from_body[b] * m);
    }
    return out;
  }
};

std::expected<Crowd, std::string> make_crowd(const ScaleArgs& a, const StarSet& set, const StarSet& hand_set, const Box& box) {
  if (set.stars.size() < static_cast<std::size_t>(a.bodies)) {
    return std::unexpected("--bodies " + std::to_string(a.bodies) + ": " + a.set_file + " has only " + std::to_string(set.stars.size()) +
                           " stars");
  }
  if (hand_set.stars.size() < static_cast<std::size_t>(a.hands)) {
    return std::unexpected("--hands " + std::to_string(a.hands) + ": " + a.hand_set_file + " has only " +
                           std::to_string(hand_set.stars.size()) + " stars");
  }
  Crowd crowd;
  const int people = std::max(1, (std::max(a.hands, a.bodies) + 1) / 2);
  crowd.people = walkers(people, box.centre - box.size / 2, box.centre + box.size / 2, a.seed + 1);
  std::array<HandLayout, 2> base;
  for (std::size_t s = 0; s < 2; ++s) {
    auto layout =
        load_hand_layout(std::filesystem::path(RHOT_ASSET_DIR) / "hands" / (s == 0 ? "low-cost-left.json" : "low-cost-right.json"));
    if (!layout) return std::unexpected(layout.error());
    base[s] = std::move(*layout);
  }
  const auto motions = hand_motion_names();
  for (int h = 0; h < a.hands; ++h) {
    CrowdHand hand;
    const std::size_t side = static_cast<std::size_t>(h % 2);
    hand.layout = base[side];
    hand.layout.name = "crowd-" + std::to_string(h);
    // The hand set's star on the back of the hand, where the layout's own sits (about 15 mm above
    // the wrist's frame, between the wrist and the knuckles).
    const MarkerStar& star = hand_set.stars[static_cast<std::size_t>(h)];
    for (std::size_t m = 0; m < 4; ++m) {
      const Eigen::Vector3d mm = star.markers_mm[m];
      hand.layout.markers[m].offset_m = 1e-3 * Eigen::Vector3d(mm.x(), 15.0 + mm.y(), mm.z() - 95.0);
    }
    hand.layout.marker_diameter_mm = hand_set.rules.marker_diameter_mm;
    hand.skeleton = reference_open_hand(hand.layout.side);
    hand.chains = hand_chains(hand.skeleton, hand.layout.side);
    hand.relaxed = HandSolver(hand.layout.side, hand.skeleton).state().angles;
    hand.motion = motions[static_cast<std::size_t>(h / 2) % motions.size()];
    hand.person = h / 2;
    hand.person_from_hand_m = {side == 0 ? -0.25 : 0.25, 1.1, 0.3};
    crowd.hands.push_back(std::move(hand));
  }
  for (int b = 0; b < a.bodies; ++b) {
    std::array<Eigen::Vector3d, 4> markers;
    for (std::size_t m = 0; m < 4; ++m) markers[m] = 1e-3 * set.stars[static_cast<std::size_t>(b)].markers_mm[m];
    crowd.body_markers_m.push_back(markers);
    crowd.body_person.push_back(b % people);
    crowd.body_turn_hz.push_back(0.1 + 0.05 * static_cast<double>(b % 5));
  }
  return crowd;
}

// FNV-1a over a vector's bytes: equal runs fold to equal values.
void fold(std::uint64_t& hash, const Eigen::Vector3d& v) {
  const auto* bytes = reinterpret_cast<const unsigned char*>(v.data());
  for (std::size_t k = 0; k < sizeof(double) * 3; ++k) {
    hash ^= bytes[k];
    hash *= 1099511628211ULL;
  }
}

// Loose markers: those --markers leaves after the hands' and the props' (none when they alone exceed it).
int loose_markers(const ScaleArgs& a) { return std::max(0, a.markers - static_cast<int>(kHandMarkers) * a.hands - 4 * a.bodies); }

double resident_mb() {
  std::ifstream statm("/proc/self/statm");
  long pages = 0;
  long resident = 0;
  if (!(statm >> pages >> resident)) return 0.0;
  return static_cast<double>(resident) * static_cast<double>(sysconf(_SC_PAGESIZE)) / (1024.0 * 1024.0);
}

// One run's timings (per frame, judged frames only) and what it delivered.
struct Run {
  std::array<std::vector<double>, 3> stage_ms;  // matching, stars, hands
  std::vector<double> frame_ms;
  long findable = 0, found = 0;
  long body_frames = 0, body_correct = 0;
  long hand_frames = 0, hand_correct = 0, tips_correct = 0;
  double joint_error_sum_m = 0.0;
  long joint_errors = 0;
  std::uint64_t fingerprint = 14695981039346656037ULL;  // FNV-1a of every point and joint, to compare thread counts
  double resident_mb_warm = 0.0, resident_mb_end = 0.0;
  // Heap allocations per stage over the judged frames (AllocationCount.h), and the frames with any.
  std::array<std::uint64_t, 3> stage_allocations{};
  long allocating_frames = 0;
  std::uint64_t warm_up_allocations = 0;  // the same over the warm-up's frames
  bool allocations_counted = false;       // whether this build counts them (AllocationCount.h)
};

// One judged frame against the truth: the markers found, the bodies and the hands correct.
void judge_frame(const RigFrame& frame, std::span<const MatchedPoint> matched, const std::vector<TrackedStar>& tracked,
                 const std::vector<HandTracker*>& hand_ptrs, const Crowd& crowd, Run& run) {
  // Found markers, as rhot-eval triangulation counts them.
  std::vector<int> seen_by(frame.truth_position_m.size(), 0);
  for (const CameraFrame& cf : frame.cameras) {
    for (const Detection& d : cf.detections)
      if (d.truth_marker >= 0) ++seen_by[static_cast<std::size_t>(d.truth_marker)];
  }
  for (const int n : seen_by) run.findable += n >= 2 ? 1 : 0;
  for (const MatchedPoint& m : matched) run.found += truth_marker(frame, m) >= 0 ? 1 : 0;
  const Truth truth = crowd.truth_at(frame.time_s);
  for (std::size_t b = 0; b < crowd.body_markers_m.size(); ++b) {
    const TrackedStar& s = tracked[b];
    ++run.body_frames;
    if (s.measured_now() && (s.world_from_star.translation - truth.world_from_body[b].translation).norm() <= kBodyCorrect_m)
      ++run.body_correct;
  }
  for (std::size_t h = 0; h < hand_ptrs.size(); ++h) {
    const TrackedHand& hand = hand_ptrs[h]->last();
    ++run.hand_frames;
    if (!hand.hand_seen) continue;
    const auto error = [&](HandJoint j) {
      const auto k = static_cast<std::size_t>(j);
      return (hand.joints_world[k] - truth.world_from_hand[h] * truth.hand_pose[h].position_m[k]).norm();
    };
    if (error(HandJoint::kWrist) > kWristCorrect_m) continue;
    ++run.hand_correct;
    bool tips = true;
    for (const HandJoint tip :
         {HandJoint::kThumbTip, HandJoint::kIndexTip, HandJoint::kMiddleTip, HandJoint::kRingTip, HandJoint::kLittleTip})
      tips = tips && error(tip) <= kTipCorrect_m;
    run.tips_correct += tips ? 1 : 0;
    for (int j = 0; j < kHandJointCount; ++j) {
      run.joint_error_sum_m += error(static_cast<HandJoint>(j));  // over the correct hands
      ++run.joint_errors;
    }
  }
}

Run run_crowd(const ScaleArgs& a, const CameraRig& rig, const StarSet& set, const StarSet& hand_set, const Crowd& crowd, const Box& box,
              int threads, bool verbose) {
  SimulatedRigSettings settings;
  settings.sigma_px = a.sigma;
  settings.dropout = a.dropout;
  settings.seed = a.seed;
  settings.rate_hz = a.rate_hz;
  const int loose = loose_markers(a);
  SimulatedRig sim(rig, random_trajectories(loose, box.centre - box.size / 2, box.centre + box.size / 2, a.seed + 2), settings);
  sim.set_scripted_markers([&](double t) { return crowd.markers(crowd.truth_at(t)); });
  // One library: the props' stars (ids 0 .. bodies - 1), then the hands' (the set's next ones).
  StarSet library = set;
  library.stars.resize(static_cast<std::size_t>(a.bodies));
  // Edges are told apart to the finer of the two sets' variations.
  library.rules.variation_mm = std::min(set.rules.variation_mm, hand_set.rules.variation_mm);
  std::vector<int> hand_star;
  for (const CrowdHand& h : crowd.hands) {
    MarkerStar star = h.layout.hand_star_set().stars[0];
    star.id = static_cast<int>(library.stars.size());
    hand_star.push_back(star.id);
    library.stars.push_back(star);
  }
  StarTracker stars(StarLibrary{library});
  for (const int s : hand_star) stars.set_motion(s, hand_star_motion());
  std::vector<std::unique_ptr<HandTracker>> trackers;
  std::vector<HandTracker*> hand_ptrs;
  for (const CrowdHand& h : crowd.hands) {
    trackers.push_back(std::make_unique<HandTracker>(h.layout, h.skeleton));
    hand_ptrs.push_back(trackers.back().get());
  }
  std::optional<JobPool> jobs;
  if (threads > 1) jobs.emplace(threads);
  JobPool* pool = jobs ? &*jobs : nullptr;
  PixelSigmaEstimate pixel_sigma;
  std::vector<bool> taken;
  // What each frame's stages hand on, kept from frame to frame as the runtime keeps them.
  std::vector<Eigen::Vector3d> points;
  std::vector<double> sigmas;
  Run run;
  const int frames = std::max(1, static_cast<int>(std::lround(a.seconds * a.rate_hz)));
  const int warm = std::min(frames - 1, static_cast<int>(std::lround(kWarmUp_s * a.rate_hz)));
  // The record of the judged frames' times, every page of it written now: the resident memory
  // after the warm-up then holds it, and what grows after is the tracking's own.
  for (auto& ms : run.stage_ms) ms.assign(static_cast<std::size_t>(frames - warm), 0.0);
  run.frame_ms.assign(static_cast<std::size_t>(frames - warm), 0.0);
  run.allocations_counted = counting_heap_allocations();
  using Clock = std::chrono::steady_clock;
  const auto ms = [](Clock::time_point from, Clock::time_point to) { return std::chrono::duration<double, std::milli>(to - from).count(); };
  RigMatcher matcher(rig);
  for (int f = 0; f < frames; ++f) {
    const RigFrame frame = sim.next();
    const std::uint64_t a0 = heap_allocations();
    const auto t0 = Clock::now();
    MatchSettings match_settings = match_settings_for(pixel_sigma.sigma_px());
    match_settings.follow_points = a.follow;
    const std::span<const MatchedPoint> matched = matcher.match_frame(frame, match_settings, pool);
    point_sigmas_m(matched, pixel_sigma.update(matched), sigmas);
    points.clear();
    for (const MatchedPoint& m : matched) points.push_back(m.point.position_world);
    const auto t1 = Clock::now();
    const std::uint64_t a1 = heap_allocations();
    const std::vector<TrackedStar>& tracked = stars.update(frame.time_s, points, sigmas);
    const auto t2 = Clock::now();
    const std::uint64_t a2 = heap_allocations();
    track_hands(hand_ptrs, hand_star, tracked, frame.time_s, points, sigmas, taken, {}, pool);
    const auto t3 = Clock::now();
    const std::uint64_t a3 = heap_allocations();
    if (f < warm) run.warm_up_allocations += a3 - a0;
    if (f >= warm) {
      run.stage_allocations[0] += a1 - a0;
      run.stage_allocations[1] += a2 - a1;
      run.stage_allocations[2] += a3 - a2;
      run.allocating_frames += a3 != a0 ? 1 : 0;
    }
    if (f == warm) run.resident_mb_warm = resident_mb();
    if (verbose && frames >= 20 && (f + 1) % (frames / 10) == 0)
      std::cerr << "rhot-eval: frame " << f + 1 << " of " << frames << " (" << threads << " thread" << (threads == 1 ? "" : "s")
                << "), resident " << std::round(resident_mb() * 10.0) / 10.0 << " MB\n";
    for (const Eigen::Vector3d& p : points) fold(run.fingerprint, p);
    for (const HandTracker* h : hand_ptrs) {
      for (const Eigen::Vector3d& j : h->last().joints_world) fold(run.fingerprint, j);
    }
    if (f < warm) continue;
    const auto judged = static_cast<std::size_t>(f - warm);
    run.stage_ms[0][judged] = ms(t0, t1);
    run.stage_ms[1][judged] = ms(t1, t2);
    run.stage_ms[2][judged] = ms(t2, t3);
    run.frame_ms[judged] = ms(t0, t3);
    judge_frame(frame, matched, tracked, hand_ptrs, crowd, run);
  }
  run.resident_mb_end = resident_mb();
  return run;
}

double mean(const std::vector<double>& v) {
  double s = 0.0;
  for (const double x : v) s += x;
  return v.empty() ? 0.0 : s / static_cast<double>(v.size());
}

}  // namespace

int scale(const ScaleArgs& a) {
  const auto rig = load_rig(a.rig_file);
  if (!rig) {
    std::cerr << "rhot-eval: " << rig.error() << "\n";
    return 1;
  }
  const auto set = load_star_set(a.set_file);
  if (!set) {
    std::cerr << "rhot-eval: " << set.error() << "\n";
    return 1;
  }
  const auto hand_set = load_star_set(a.hand_set_file);
  if (!hand_set) {
    std::cerr << "rhot-eval: " << hand_set.error() << "\n";
    return 1;
  }
  const Box box = evaluation_box(*rig, {}, {});
  const auto crowd = make_crowd(a, *set, *hand_set, box);
  if (!crowd) {
    std::cerr << "rhot-eval: " << crowd.error() << "\n";
    return 1;
  }
  const int threads = threads_or_all(a.threads);
  const Run run = run_crowd(a, *rig, *set, *hand_set, *crowd, box, threads, true);
  std::optional<Run> one;
  if (threads > 1) one = run_crowd(a, *rig, *set, *hand_set, *crowd, box, 1, true);
  const double period_ms = 1000.0 / a.rate_hz;
  nlohmann::json j;
  j["rig"] = a.rig_file;
  j["set"] = a.set_file;
  j["hand_set"] = a.hand_set_file;
  j["cameras"] = rig->cameras.size();
  // What was tracked: the hands' and props' markers, and loose ones up to --markers (none below it).
  j["markers"] = static_cast<int>(kHandMarkers) * a.hands + 4 * a.bodies + loose_markers(a);
  j["people"] = crowd->people.size();
  j["bodies"] = a.bodies;
  j["hands"] = a.hands;
  j["threads"] = threads;
  j["follow"] = a.follow;
  j["rate_hz"] = a.rate_hz;
  j["seconds"] = a.seconds;
  j["seed"] = a.seed;
  j["sigma_px"] = a.sigma;
  j["judged_frames"] = run.frame_ms.size();
  // Allocations per judged frame; null where this build cannot count them.
  const auto per_frame = [&](std::uint64_t n) {
    if (!run.allocations_counted) return nlohmann::json(nullptr);
    return nlohmann::json(run.frame_ms.empty() ? 0.0 : static_cast<double>(n) / static_cast<double>(run.frame_ms.size()));
  };
  const std::array<const char*, 3> names{"matching", "stars", "hands"};
  for (std::size_t s = 0; s < names.size(); ++s) {
    j["stages"][names[s]] = {{"p50_ms", percentile(run.stage_ms[s], 0.5)},
                             {"p99_ms", percentile(run.stage_ms[s], 0.99)},
                             {"allocations_per_frame", per_frame(run.stage_allocations[s])}};
  }
  // The heap allocations of the three stages together (AllocationCount.h), over the judged frames.
  j["allocations_per_frame"] = per_frame(run.stage_allocations[0] + run.stage_allocations[1] + run.stage_allocations[2]);
  j["allocating_frames"] = run.allocations_counted ? nlohmann::json(run.allocating_frames) : nlohmann::json(nullptr);
  j["warm_up_allocations"] = run.allocations_counted ? nlohmann::json(run.warm_up_allocations) : nlohmann::json(nullptr);
  j["frame_p50_ms"] = percentile(run.frame_ms, 0.5);
  j["frame_p99_ms"] = percentile(run.frame_ms, 0.99);
  const auto missed = std::count_if(run.frame_ms.begin(), run.frame_ms.end(), [&](double ms) { return ms > period_ms; });
  j["missed_period_fraction"] = run.frame_ms.empty() ? 0.0 : static_cast<double>(missed) / static_cast<double>(run.frame_ms.size());
  // A fraction of nothing (no markers, bodies or hands to judge) is null.
  const auto fraction = [](long part, long whole) {
    return whole > 0 ? nlohmann::json(static_cast<double>(part) / static_cast<double>(whole)) : nlohmann::json(nullptr);
  };
  j["found_fraction"] = fraction(run.found, run.findable);
  j["bodies_correct_fraction"] = fraction(run.body_correct, run.body_frames);
  j["hands_correct_fraction"] = fraction(run.hand_correct, run.hand_frames);
  // Of the hands judged correct (seen, the wrist where it is), those whose five fingertips are within
  // 20 mm too: what the rig's resolution allows fingers (stage-32's cameras see a centimetre a pixel
  // from six metres).
  j["fingertips_correct_fraction"] = fraction(run.tips_correct, run.hand_correct);
  j["hand_joint_error_mean_mm"] = run.joint_errors > 0
                                      ? nlohmann::json(1000.0 * run.joint_error_sum_m / static_cast<double>(run.joint_errors))
                                      : nlohmann::json(nullptr);
  j["speedup_vs_one_thread"] = one ? mean(one->frame_ms) / std::max(mean(run.frame_ms), 1e-9) : 1.0;
  if (one) {
    j["one_thread_frame_p99_ms"] = percentile(one->frame_ms, 0.99);
    j["same_results_as_one_thread"] = one->fingerprint == run.fingerprint;
  }
  j["resident_mb_after_warm_up"] = run.resident_mb_warm;
  j["resident_mb_end"] = run.resident_mb_end;
  std::cout << j.dump(2) << "\n";
  return 0;
}

}  // namespace rhot::eval
