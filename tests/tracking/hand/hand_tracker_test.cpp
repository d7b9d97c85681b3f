#include "tracking/hand/HandTracker.h"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <random>
#include <set>

#include <gtest/gtest.h>

#include "tests/support/TempDir.h"
#include "tracking/camera/RigFile.h"
#include "tracking/core/MarkerColour.h"
#include "tracking/geometry/Matching.h"
#include "tracking/hand/HandCalibration.h"
#include "tracking/sim/HandMotions.h"
#include "tracking/sim/Realism.h"
#include "tracking/sim/SimulatedRig.h"

namespace rhot {
namespace {

namespace fs = std::filesystem;

HandLayout shipped_layout(const std::string& name) {
  auto layout = load_hand_layout(fs::path(RHOT_ASSET_DIR) / "hands" / (name + ".json"));
  EXPECT_TRUE(layout.has_value()) << (layout ? "" : layout.error());
  return layout.value_or(HandLayout{});
}

HandLayout low_cost() { return shipped_layout("low-cost-right"); }

// The layout's markers for a true hand (world frame), without noise.
std::vector<Eigen::Vector3d> markers(const HandLayout& layout, const Rigid3d& world_from_hand, const HandPose& pose) {
  return layout_markers(layout, world_from_hand, pose);
}

TEST(HandLayout, TheLowCostLayoutLoads) {
  const HandLayout layout = low_cost();
  EXPECT_EQ(layout.name, "low-cost");
  EXPECT_EQ(layout.side, HandSide::kRight);
  ASSERT_EQ(layout.hand_frame_markers, 4U);
  ASSERT_EQ(layout.markers.size(), 9U);
  for (int f = 0; f < kFingerCount; ++f) ASSERT_EQ(layout.fingertip_marker[static_cast<std::size_t>(f)], 4 + f);
  EXPECT_EQ(layout.fingertip(1)->name, "index_tip");
  EXPECT_EQ(layout.fingertip(1)->bone, HandJoint::kIndexTip);
  EXPECT_TRUE(layout.fingertip(1)->offset_m.isApprox(Eigen::Vector3d(0.0, 0.0, -0.008)));
}

TEST(HandLayout, TheHighFidelityLayoutPutsAStarOnEveryFingerBone) {
  const HandLayout layout = shipped_layout("high-fidelity-right");
  EXPECT_EQ(layout.name, "high-fidelity");
  ASSERT_EQ(layout.segment_stars.size(), 15U);
  std::set<HandJoint> bones;
  std::set<int> ids;
  for (const SegmentStar& s : layout.segment_stars) {
    bones.insert(s.bone);
    ids.insert(s.star.id);
    const auto joints = chain_joints(finger_of_bone(s.bone));
    EXPECT_NE(std::find(joints.begin(), joints.begin() + 3, s.bone), joints.begin() + 3) << joint_name(s.bone);
  }
  EXPECT_EQ(bones.size(), 15U);
  EXPECT_EQ(ids.size(), 15U);
  for (const int m : layout.fingertip_marker) EXPECT_EQ(m, -1);
  EXPECT_EQ(layout.markers.size(), 4U);
  EXPECT_DOUBLE_EQ(layout.segment_star_rules.variation_mm, 1.5);
}

std::string layout_error(const std::string& text) {
  // A folder of this test's own (tests/support/TempDir.h): the tests of this program run side by
  // side, each in its process.
  const fs::path file = test::fresh_test_dir("rhot_bad_layout") / "layout.json";
  std::ofstream(file) << text;
  const auto r = load_hand_layout(file);
  if (r) return "loaded";
  // "FILE: /pointer: message", or "FILE:line:col: message" for syntax errors.
  std::string e = r.error().substr(file.string().size());
  return e.substr(e.rfind(": ", 0) == 0 ? 2 : 1);
}

TEST(HandLayout, BadFilesAreRefusedWithWhatIsWrong) {
  const std::string head = R"("format": "rhot-hand-layout", "version": 1, "side": "right", "marker_diameter_mm": 6)";
  const std::string star = R"("hand_star_mm": [[20.1, 17.7, -69.5], [-17.7, 21.9, -17.7], [0.0, 12.4, -56.0], [-4.3, 17.0, -22.4]])";
  EXPECT_EQ(layout_error("{" + head + ", " + star + "}"), "loaded");
  EXPECT_EQ(layout_error(R"({"format": "hand"})"), "/format: expected \"rhot-hand-layout\", got \"hand\"");
  EXPECT_EQ(layout_error(R"({"format": "rhot-hand-layout", "version": 1, "side": "middle"})"),
            "/side: expected \"left\" or \"right\", got \"middle\"");
  EXPECT_EQ(layout_error("{" + head + "}"), "/: missing required key \"markers\" (or the earlier form's \"hand_star_mm\")");
  EXPECT_EQ(layout_error("{" + head + R"(, "hand_star_mm": [[1, 2, 3]]})"),
            "/hand_star_mm: expected four [x, y, z] marker centres, got an array");
  EXPECT_EQ(layout_error(R"({"format": "rhot-hand-layout", "version": 1, "side": "right", "marker_diameter_mm": -6})"),
            "/marker_diameter_mm: expected a number greater than 0 (and within float range), got -6");
  EXPECT_EQ(layout_error("{" + head + ", " + star + R"(, "colour": "red"})"),
            "/colour: unknown key \"colour\"; expected one of: format, version, name, side, marker_diameter_mm, markers, hand_star_mm, "
            "fingertip_markers, star_set, segment_stars, description, marker_colours");
  EXPECT_EQ(layout_error("{" + head + ", " + star + ", " + star + "}"), "/hand_star_mm: duplicate key \"hand_star_mm\"");
  EXPECT_EQ(layout_error("{" + head),  // The text ends after 85 characters: the parser stops at column 86.
            "1:86: invalid JSON: syntax error while parsing object - unexpected end of input; expected '}'");
  EXPECT_EQ(layout_error("{" + head + ", " + star + R"(, "fingertip_markers": {"index_knuckle": 8})" + "}"),
            "/fingertip_markers/index_knuckle: not a fingertip joint (thumb_tip, index_tip, middle_tip, ring_tip, little_tip)");
  EXPECT_EQ(layout_error("{" + head + R"(, "hand_star_mm": [[0, 0, 0], [10, 0, 0], [0, 10, 0], [0, 0, 30]]})"),
            "/hand_star_mm: edges 10 and 10 mm differ by less than 1.5 mm");
  const std::string set = R"("star_set": ")" + (fs::path(RHOT_ASSET_DIR) / "stars" / "seed-case.json").string() + "\"";
  const auto segments = [&](const std::string& list) {
    return "{" + head + ", " + star + ", " + set + R"(, "segment_stars": )" + list + "}";
  };
  EXPECT_EQ(layout_error(segments(R"([{"bone": "index_proximal", "star_id": 3}])")), "loaded");
  EXPECT_EQ(layout_error("{" + head + ", " + star + R"(, "segment_stars": []})"),
            "/: missing \"star_set\", the path of the segment stars' set");
  EXPECT_EQ(layout_error(segments(R"([{"bone": "index_metacarpal", "star_id": 3}])")),
            "/segment_stars/0/bone: expected a finger bone named by its first joint (index_proximal, thumb_metacarpal, ...)");
  EXPECT_EQ(layout_error(segments(R"([{"bone": "index_proximal", "star_id": 300}])")), "/segment_stars/0/star_id: no star 300 in the set");
  EXPECT_EQ(layout_error(segments(R"([{"bone": "index_proximal", "star_id": 3}, {"bone": "index_proximal", "star_id": 4}])")),
            "/segment_stars/1/bone: index_proximal has a star already");
  EXPECT_EQ(layout_error(segments(R"([{"bone": "index_proximal", "star_id": 3}, {"bone": "index_distal", "star_id": 3}])")),
            "/segment_stars/1/star_id: star 3 is on another bone already");
}

TEST(HandTracker, FollowsAScriptedHandFromItsMarkers) {
  const HandLayout layout = low_cost();
  const HandPose skeleton = reference_open_hand(HandSide::kRight);
  const auto chains = hand_chains(skeleton, HandSide::kRight);
  const auto relaxed = HandSolver(HandSide::kRight, skeleton).state().angles;
  HandTracker tracker(layout, skeleton);
  double worst_tip = 0.0;
  for (int f = 0; f < 180; ++f) {
    const double t = f / 90.0;
    const HandMotionFrame truth = *hand_motion("pinch", t, chains, relaxed, {0.0, 1.1, -0.45});
    const HandPose pose = hand_pose_from_angles(skeleton, chains, truth.angles);
    std::vector<Eigen::Vector3d> points = markers(layout, truth.world_from_hand, pose);
    points.push_back({0.3, 1.0, -0.2});  // a stray marker
    const TrackedHand& hand = tracker.update(t, points);
    ASSERT_TRUE(hand.hand_seen) << f;
    for (int k = 0; k < kFingerCount; ++k) {
      EXPECT_EQ(hand.fingertip_point[static_cast<std::size_t>(k)], 4 + k) << "frame " << f << " finger " << k;
      const auto tip = static_cast<std::size_t>(chain_joints(static_cast<Finger>(k))[3]);
      worst_tip = std::max(worst_tip, (hand.joints_world[tip] - truth.world_from_hand * pose.position_m[tip]).norm());
    }
  }
  EXPECT_LT(worst_tip, 0.002) << "noise-free markers: the tips within 2 mm (IK tolerance and marker offset)";
}

// A power grasp of a hand with its own bones and angles (not the model's), each fingertip marker
// hidden in turn for 0.5 s, then all seen for 0.5 s, after 4 s with all seen: the mean and worst
// error of the hidden tips, and the frames the tracker's fingertip model was fitted to by the end.
struct HiddenTipRun {
  double mean_mm = 0.0, worst_mm = 0.0;
  int hidden_frames = 0, model_frames = 0;
  int predicted_confidence_frames = 0;
};
HiddenTipRun hide_each_fingertip_in_turn(bool fingertip_model, unsigned seed) {
  const HandLayout layout = low_cost();
  const HandPose skeleton = reference_open_hand(HandSide::kRight);
  const auto chains = hand_chains(skeleton, HandSide::kRight);
  const auto relaxed = HandSolver(HandSide::kRight, skeleton).state().angles;
  const HandPose user = independent_hand(skeleton, seed);
  const auto user_chains = hand_chains(user, HandSide::kRight);
  HandTrackerSettings settings;
  settings.fingertip_model = fingertip_model;
  HandTracker tracker(layout, skeleton, settings);
  HiddenTipRun run;
  double sum = 0.0;
  for (int f = 0; f < 1260; ++f) {
    const double t = f / 90.0;
    const HandMotionFrame truth = *hand_motion("power-grasp", t, chains, relaxed, {0.0, 1.1, -0.45});
    const HandPose pose = hand_pose_from_angles(user, user_chains, independent_angles(truth.angles, seed));
    std::vector<Eigen::Vector3d> points = markers(layout, truth.world_from_hand, pose);
    const int gap = f >= 360 ? (f - 360) / 45 : -1;
    const int hidden = gap >= 0 && gap % 2 == 0 ? gap / 2 % kFingerCount : -1;
    if (hidden >= 0) points.erase(points.begin() + 4 + hidden);
    const TrackedHand& hand = tracker.update(t, points);
    if (hidden < 0 || !hand.hand_seen) continue;
    const auto tip = static_cast<std::size_t>(chain_joints(static_cast<Finger>(hidden))[3]);
    const double e = 1000.0 * (hand.joints_world[tip] - truth.world_from_hand * pose.position_m[tip]).norm();
    sum += e;
    run.worst_mm = std::max(run.worst_mm, e);
    ++run.hidden_frames;
    if (hand.state.confidence[tip] == HandSolver::kPredictedConfidence) ++run.predicted_confidence_frames;
  }
  run.mean_mm = sum / std::max(run.hidden_frames, 1);
  run.model_frames = tracker.fingertip_model_frames();
  return run;
}

TEST(HandTracker, AHiddenFingertipIsPlacedWhereTheSeenOnesSayItIs) {
  for (const unsigned seed : {1u, 2u}) {
    const HiddenTipRun model = hide_each_fingertip_in_turn(true, seed), rule = hide_each_fingertip_in_turn(false, seed);
    SCOPED_TRACE(::testing::Message() << "seed " << seed << ": hidden tips " << model.mean_mm << " mm mean, " << model.worst_mm
                                      << " mm worst with the model; " << rule.mean_mm << ", " << rule.worst_mm << " by the rule");
    const std::string key = "seed" + std::to_string(seed) + "_";
    ::testing::Test::RecordProperty(key + "model_mean_mm", std::to_string(model.mean_mm));
    ::testing::Test::RecordProperty(key + "model_worst_mm", std::to_string(model.worst_mm));
    ::testing::Test::RecordProperty(key + "rule_mean_mm", std::to_string(rule.mean_mm));
    ::testing::Test::RecordProperty(key + "rule_worst_mm", std::to_string(rule.worst_mm));
    EXPECT_GT(model.hidden_frames, 300);
    EXPECT_GE(model.model_frames, HandTracker::kFingertipModelFrames) << "fitted from the frames with all five seen";
    EXPECT_EQ(rule.model_frames, 0);
    EXPECT_GT(model.predicted_confidence_frames, 0.9 * model.hidden_frames) << "a predicted tip says so";
    // Measured: 3.3 and 1.6 mm mean, 8.0 and 4.5 mm worst with the model; 5.8 and 7.4 mm mean, 14.6
    // and 24.3 mm worst by the rule (the hidden finger bent at the others' rate times the coupling
    // learnt while it was seen: HandSolver::coupling). Bent at the others' very rate, as the rule
    // did before, it was 39 and 31 mm worst.
    EXPECT_LT(model.mean_mm, 5.0);
    EXPECT_LT(model.worst_mm, 15.0);
    EXPECT_LT(model.mean_mm, 0.6 * rule.mean_mm);
    EXPECT_LT(model.worst_mm, 0.6 * rule.worst_mm);
    EXPECT_LT(rule.worst_mm, 27.0) << "the rule with its learnt coupling";
  }
}

// A finger whose estimate went astray while its marker was hidden: the index finger curls fully
// behind something while the other fingers hold still (so the rule holds it where it was last
// seen, open), and its marker comes back 60 mm and more from that estimate, outside every gate.
// Followed by its estimate alone, it would stay lost as long as it stays curled; its finger
// reaches the free point, which is there two frames running, so it is found again.
TEST(HandTracker, AFingerWhoseEstimateWentAstrayFindsItsMarkerAgainByReach) {
  const HandLayout layout = low_cost();
  const HandPose skeleton = reference_open_hand(HandSide::kRight);
  const auto chains = hand_chains(skeleton, HandSide::kRight);
  const auto relaxed = HandSolver(HandSide::kRight, skeleton).state().angles;
  const Rigid3d world_from_hand{Eigen::Quaterniond::Identity(), Eigen::Vector3d(0.0, 1.1, -0.45)};
  HandTracker tracker(layout, skeleton);
  auto curled = relaxed;
  curled[1].flexion_rad = {1.3, 1.5, 1.0};
  const auto index_tip = static_cast<std::size_t>(chain_joints(Finger::kIndex)[3]);
  double astray_mm = 0.0;
  int found_at = -1;
  for (int f = 0; f < 180; ++f) {
    const double t = f / 90.0;
    // Frames 0-59 open and seen; 60-89 curling, hidden; from 90 curled and seen again.
    const double s = std::clamp((f - 60) / 30.0, 0.0, 1.0);
    auto angles = relaxed;
    for (std::size_t k = 0; k < 3; ++k)
      angles[1].flexion_rad[k] = relaxed[1].flexion_rad[k] + s * (curled[1].flexion_rad[k] - relaxed[1].flexion_rad[k]);
    const HandPose pose = hand_pose_from_angles(skeleton, chains, angles);
    std::vector<Eigen::Vector3d> points = markers(layout, world_from_hand, pose);
    if (f >= 60 && f < 90) points.erase(points.begin() + 5);  // the index tip's marker
    const TrackedHand& hand = tracker.update(t, points);
    ASSERT_TRUE(hand.hand_seen) << "frame " << f;
    const double e = 1000.0 * (hand.joints_world[index_tip] - world_from_hand * pose.position_m[index_tip]).norm();
    if (f == 89) astray_mm = e;
    if (f >= 90 && found_at < 0 && hand.state.tip_seen[1]) found_at = f;
    if (found_at >= 0 && f >= found_at) {
      EXPECT_TRUE(hand.state.tip_seen[1]) << "frame " << f;
      EXPECT_LT(e, 3.0) << "frame " << f;
      // Not trusted while reach has just found it; measured once it has been followed a while.
      EXPECT_DOUBLE_EQ(hand.state.confidence[index_tip],
                       f < found_at + HandTracker::kReacquiredFrames ? HandTracker::kReacquiredConfidence : 1.0)
          << "frame " << f;
    }
  }
  EXPECT_GT(astray_mm, 1000.0 * HandTracker::kFingertipGateMax_m) << "the estimate went outside every gate";
  EXPECT_GE(found_at, 90);
  EXPECT_LE(found_at, 91) << "found again once the point was there two frames running";
}

// A user's finger longer than the skeleton's (the runtime's trackers run the reference hand, and
// users' hands span about +-10 % around it): the index, 10 % longer, curled while seen and
// straightened while its marker is hidden, the other fingers still (so its estimate stays curled).
// Its marker comes back outside every gate of that estimate and, straight, farther from the
// knuckle than the skeleton's index reaches. The first frame from 90 at which the index has it
// again (-1: never), and the index tip's worst error from then on.
struct LongerFinger {
  int found_at = -1;
  double worst_after_mm = 0.0;
};
LongerFinger longer_index_straightened_while_hidden(double tolerance) {
  const HandLayout layout = low_cost();
  const HandPose skeleton = reference_open_hand(HandSide::kRight);
  HandPose user = skeleton;
  const auto joints = chain_joints(Finger::kIndex);
  const Eigen::Vector3d knuckle = skeleton.position_m[static_cast<std::size_t>(joints[0])];
  for (std::size_t k = 1; k < joints.size(); ++k) {
    const auto j = static_cast<std::size_t>(joints[k]);
    user.position_m[j] = knuckle + 1.1 * (skeleton.position_m[j] - knuckle);
  }
  const auto user_chains = hand_chains(user, HandSide::kRight);
  const auto relaxed = HandSolver(HandSide::kRight, skeleton).state().angles;
  const Rigid3d world_from_hand{Eigen::Quaterniond::Identity(), Eigen::Vector3d(0.0, 1.1, -0.45)};
  HandTrackerSettings settings;
  settings.finger_length_tolerance = tolerance;
  HandTracker tracker(layout, skeleton, settings);
  const std::array<double, 3> curled{1.2, 1.4, 0.9};
  const auto index_tip = static_cast<std::size_t>(joints[3]);
  LongerFinger out;
  for (int f = 0; f < 150; ++f) {
    // Frames 0-59 curled and seen; 60-89 straightening, hidden; from 90 straight and seen again.
    const double s = std::clamp((f - 60) / 30.0, 0.0, 1.0);
    auto angles = relaxed;
    for (std::size_t k = 0; k < 3; ++k) angles[1].flexion_rad[k] = (1.0 - s) * curled[k];  // straight at the end
    const HandPose pose = hand_pose_from_angles(user, user_chains, angles);
    std::vector<Eigen::Vector3d> points = markers(layout, world_from_hand, pose);
    if (f >= 60 && f < 90) points.erase(points.begin() + 5);  // the index tip's marker
    const TrackedHand& hand = tracker.update(f / 90.0, points);
    EXPECT_TRUE(hand.hand_seen) << "frame " << f;
    if (f < 90) continue;
    if (out.found_at < 0 && hand.fingertip_point[1] == 5) out.found_at = f;
    if (out.found_at >= 0) {
      EXPECT_EQ(hand.fingertip_point[1], 5) << "frame " << f << ": kept once found";
      out.worst_after_mm =
          std::max(out.worst_after_mm, 1000.0 * (hand.joints_world[index_tip] - world_from_hand * pose.position_m[index_tip]).norm());
    }
  }
  return out;
}

TEST(HandTracker, AFingerLongerThanTheSkeletonsFindsItsMarkerAgainByReach) {
  // Reached only at the skeleton's own length, it was never found again: the index stayed curled,
  // its marker in view (the workbench and the grasp scenarios' thumbs, their users' hands longer).
  const LongerFinger exact = longer_index_straightened_while_hidden(0.0);
  EXPECT_EQ(exact.found_at, -1);
  const LongerFinger tolerant = longer_index_straightened_while_hidden(HandTrackerSettings{}.finger_length_tolerance);  // 0.1
  EXPECT_EQ(tolerant.found_at, 91) << "found again once the point was there two frames running";
  // The skeleton's shorter index points at the marker: its tip short of the user's by about the
  // difference in length (measured: 8.2 mm at worst).
  EXPECT_LT(tolerant.worst_after_mm, 12.0);
}

// The workbench's door (seed 228): the left thumb hidden, a stray within its reach 45 mm from its
// estimate was taken for its marker by reach and followed for a few frames. The thumb, measured 41 mm
// out of the handle, let the door go. A point found by reach is now not trusted (kReacquiredConfidence,
// below a grasp's 0.95) until it has been found in kReacquiredFrames frames: here a stray there for
// seven frames but one, which a finger whose count started afresh on its return would trust.
TEST(HandTracker, AStrayTheHiddenThumbReachesForAFewFramesIsNeverTrusted) {
  const HandLayout layout = low_cost();
  const HandPose skeleton = reference_open_hand(HandSide::kRight);
  const auto chains = hand_chains(skeleton, HandSide::kRight);
  const auto relaxed = HandSolver(HandSide::kRight, skeleton).state().angles;
  const Rigid3d world_from_hand{Eigen::Quaterniond::Identity(), Eigen::Vector3d(0.0, 1.1, -0.45)};
  const HandPose pose = hand_pose_from_angles(skeleton, chains, relaxed);
  // The stray: where the thumb's marker would be with the thumb bent across the palm.
  auto bent = relaxed;
  bent[0].flexion_rad = {0.9, 0.9, 0.9};
  const Eigen::Vector3d stray = markers(layout, world_from_hand, hand_pose_from_angles(skeleton, chains, bent))[4];
  ASSERT_GT((stray - markers(layout, world_from_hand, pose)[4]).norm(), HandTracker::kFingertipGateMax_m);
  HandTracker tracker(layout, skeleton);
  const auto thumb_tip = static_cast<std::size_t>(chain_joints(Finger::kThumb)[3]);
  int taken_at = -1;
  for (int f = 0; f < 130; ++f) {
    std::vector<Eigen::Vector3d> points = markers(layout, world_from_hand, pose);
    if (f >= 60) points.erase(points.begin() + 4);                 // the thumb's marker hidden
    if (f >= 100 && f < 108 && f != 104) points.push_back(stray);  // seven frames, gone for one between
    const TrackedHand& hand = tracker.update(f / 90.0, points);
    ASSERT_TRUE(hand.hand_seen) << "frame " << f;
    if (f < 60) continue;
    if (hand.fingertip_point[0] >= 0 && taken_at < 0) taken_at = f;
    EXPECT_LT(hand.state.confidence[thumb_tip], 0.95) << "frame " << f << ": never trusted while its marker is hidden";
  }
  EXPECT_EQ(taken_at, 101) << "the stray is taken by reach, there two frames running";
}

// A hand-over (`rhot-eval grasp --hands tracked`, seeds 1-4): the two hands on the cube, each
// thumb hidden. The giving hand opens, its thumb bending while hidden; its marker comes back 17 mm
// from where that hand's estimate holds it, 12 mm from the taking hand's hidden thumb's estimate.
// Nearest first gave it to the taking hand, whose thumb followed it away and let the cube go as
// "thumb opened". Here: both hands still, both thumbs' markers hidden from frame 60; the right
// (giving) thumb bends while hidden (`bend` radians more at each joint) and is seen again from frame 100,
// `left_mm` from the left thumb's estimate (on the side away from the right's). Per frame from
// 100: whether each hand's thumb had the point.
struct ReturningThumb {
  int left_frames = 0;         // frames the left thumb held the right thumb's marker
  int right_from = -1;         // the first frame the right thumb had it back
  double right_miss_mm = 0.0;  // how far the right thumb's marker moved while hidden
};
ReturningThumb right_thumb_returning_beside_the_left(double bend, double left_mm, bool right_tracked) {
  const std::array<HandLayout, 2> layouts{shipped_layout("low-cost-left"), low_cost()};
  std::array<HandPose, 2> skeleton;
  std::array<std::array<FingerChain, kFingerCount>, 2> chains;
  std::array<std::array<FingerAngles, kFingerCount>, 2> relaxed;
  for (std::size_t h = 0; h < 2; ++h) {
    skeleton[h] = reference_open_hand(layouts[h].side);
    chains[h] = hand_chains(skeleton[h], layouts[h].side);
    relaxed[h] = HandSolver(layouts[h].side, skeleton[h]).state().angles;
  }
  const auto right_pose = [&](double s) {
    auto angles = relaxed[1];
    for (std::size_t k = 0; k < 3; ++k) angles[0].flexion_rad[k] += s * bend;
    return hand_pose_from_angles(skeleton[1], chains[1], angles);
  };
  const HandPose left_pose = hand_pose_from_angles(skeleton[0], chains[0], relaxed[0]);
  const Rigid3d world_from_right{Eigen::Quaterniond::Identity(), Eigen::Vector3d(0.0, 1.1, -0.45)};
  const Eigen::Vector3d before = markers(layouts[1], world_from_right, right_pose(0.0))[4];
  const Eigen::Vector3d after = markers(layouts[1], world_from_right, right_pose(1.0))[4];
  // The left hand turned half a turn about the vertical, its thumb's marker beyond `after`.
  Rigid3d world_from_left{Eigen::Quaterniond(Eigen::AngleAxisd(std::numbers::pi, Eigen::Vector3d::UnitY())), Eigen::Vector3d::Zero()};
  const Eigen::Vector3d away = (after - before).norm() > 1e-6 ? (after - before).normalized() : Eigen::Vector3d::UnitX();
  world_from_left.translation = after + 0.001 * left_mm * away - world_from_left.rotation * markers(layouts[0], Rigid3d{}, left_pose)[4];
  StarSet both;
  for (const HandLayout& l : layouts) both.stars.push_back(l.hand_star_set().stars[0]);
  both.stars[1].id = 1;
  StarTracker stars{StarLibrary(both)};
  std::array<HandTracker, 2> trackers{HandTracker(layouts[0], skeleton[0]), HandTracker(layouts[1], skeleton[1])};
  ReturningThumb out;
  out.right_miss_mm = 1000.0 * (after - before).norm();
  for (int f = 0; f < 150; ++f) {
    const double t = f / 90.0;
    std::vector<Eigen::Vector3d> left = markers(layouts[0], world_from_left, left_pose);
    std::vector<Eigen::Vector3d> right = markers(layouts[1], world_from_right, right_pose(std::clamp((f - 60) / 40.0, 0.0, 1.0)));
    if (f >= 60) left.erase(left.begin() + 4);               // the left thumb's marker hidden from here on
    if (f >= 60 && f < 100) right.erase(right.begin() + 4);  // the right thumb's, for 40 frames
    std::vector<Eigen::Vector3d> points = left;
    points.insert(points.end(), right.begin(), right.end());
    std::vector<bool> taken;
    const std::array<HandTracker*, 2> hands{&trackers[0], &trackers[1]};
    const std::array<int, 2> star{0, 1};
    const std::size_t n = right_tracked ? 2 : 1;
    track_hands(std::span(hands.data(), n), std::span(star.data(), n), stars.update(t, points), t, points, {}, taken);
    if (f < 100) continue;
    const auto returned = static_cast<int>(points.size() - right.size() + 4);  // the right thumb's marker
    if (trackers[0].last().fingertip_point[0] == returned) ++out.left_frames;
    if (right_tracked && out.right_from < 0 && trackers[1].last().fingertip_point[0] == returned) out.right_from = f;
  }
  return out;
}

TEST(HandTracker, AMarkerComingBackBesideTheOtherHandsHiddenFingerIsNotTakenOnAGuess) {
  // The failure: the right hand not there to contest it, the left thumb takes the right's marker.
  EXPECT_GT(right_thumb_returning_beside_the_left(0.5, 12.0, false).left_frames, 40);
  // The hand-over: the right thumb's estimate, held while hidden, misses its marker by more than
  // half the left's distance; neither takes it.
  const ReturningThumb bent = right_thumb_returning_beside_the_left(0.5, 12.0, true);
  EXPECT_GT(bent.right_miss_mm, 12.0) << "the right's estimate farther from its marker than the left's: nearest first gives it the left";
  EXPECT_EQ(bent.left_frames, 0);
  // The right thumb not bent: its estimate is on its marker, and it has it back at once.
  const ReturningThumb still = right_thumb_returning_beside_the_left(0.0, 12.0, true);
  EXPECT_EQ(still.left_frames, 0);
  EXPECT_EQ(still.right_from, 100);
}

// An open hand held still, its markers seen with noise of noise_m per axis, frames 0-179; at
// frame 120 the index tip's marker is hidden and a ghost of the matching stands ghost_m from it
// (above the back of the finger, nearer no other marker). Per frame: whether the index finger had
// its own marker's point, and whether it took the ghost.
struct GhostRun {
  int own_frames = 0;  // frames the index had its marker's point (of the 179 it was there)
  bool took_ghost = false;
};
GhostRun index_beside_a_ghost(double noise_m, double ghost_m) {
  const HandLayout layout = low_cost();
  const HandPose skeleton = reference_open_hand(HandSide::kRight);
  const auto relaxed = HandSolver(HandSide::kRight, skeleton).state().angles;
  const HandPose pose = hand_pose_from_angles(skeleton, hand_chains(skeleton, HandSide::kRight), relaxed);
  const Rigid3d world_from_hand{Eigen::Quaterniond::Identity(), Eigen::Vector3d(0.0, 1.1, -0.45)};
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, noise_m);
  HandTracker tracker(layout, skeleton);
  GhostRun run;
  for (int f = 0; f < 180; ++f) {
    std::vector<Eigen::Vector3d> points = markers(layout, world_from_hand, pose);
    for (std::size_t k = 4; k < points.size(); ++k) points[k] += Eigen::Vector3d{noise(rng), noise(rng), noise(rng)};
    if (f == 120) points[5] = markers(layout, world_from_hand, pose)[5] + ghost_m * Eigen::Vector3d::UnitY();
    const TrackedHand& hand = tracker.update(f / 90.0, points);
    if (f == 120) {
      run.took_ghost = hand.fingertip_point[1] == 5;
    } else if (hand.fingertip_point[1] == 5) {
      ++run.own_frames;
    }
  }
  return run;
}

TEST(HandTracker, AFollowedFingertipRefusesAGhostBesideItsHiddenMarkerAndANoisyOneKeepsItsOwn) {
  // Where the hand model fits (markers within a millimetre of it), a ghost 19 mm from a hidden
  // fingertip marker is not taken: with the 25 mm gate every marker had, it was (in seated-4's
  // simulated fists such ghosts took a finger 10-40 mm off in 7-12 % of its seen frames).
  const GhostRun still = index_beside_a_ghost(0.0005, 0.019);
  EXPECT_FALSE(still.took_ghost);
  EXPECT_EQ(still.own_frames, 179);
  // Where it misses by more (3 mm of noise per axis: about 7 mm a frame between solve and marker,
  // as a real hand's tips miss a fitted skeleton's), the gate is wider and the marker stays found
  // every frame; with a 15 mm gate for every marker it was lost in some.
  const GhostRun noisy = index_beside_a_ghost(0.003, 0.030);
  EXPECT_FALSE(noisy.took_ghost);
  EXPECT_EQ(noisy.own_frames, 179);
}

TEST(HandTracker, TheHighFidelityLayoutMeasuresEveryBoneOfAFist) {
  // A fist hides fingertips from the cameras and defeats fingertip IK (the low-cost layout's joint
  // error is ~13 mm there); stars on the bones measure each bone's direction instead.
  const HandLayout layout = shipped_layout("high-fidelity-right");
  const HandPose skeleton = reference_open_hand(HandSide::kRight);
  const auto chains = hand_chains(skeleton, HandSide::kRight);
  const auto relaxed = HandSolver(HandSide::kRight, skeleton).state().angles;
  HandTrackerSettings settings;
  settings.filter_frame = false;  // exact stars give exact joints; a smoothed frame would lag the moving hand
  HandTracker tracker(layout, skeleton, settings);
  double worst = 0.0;
  for (int f = 0; f < 180; ++f) {
    const double t = f / 90.0;
    const HandMotionFrame truth = *hand_motion("fist", t, chains, relaxed, {0.0, 1.1, -0.45});
    const HandPose pose = hand_pose_from_angles(skeleton, chains, truth.angles);
    const TrackedHand& hand = tracker.update(t, markers(layout, truth.world_from_hand, pose));
    ASSERT_TRUE(hand.hand_seen) << f;
    if (f < 3) continue;  // three-marker acquisitions are confirmed over three frames
    EXPECT_EQ(hand.segment_stars_seen, 15) << f;
    for (std::size_t j = 0; j < kHandJointCount; ++j) {
      EXPECT_DOUBLE_EQ(hand.state.confidence[j], 1.0) << f << " " << joint_name(static_cast<HandJoint>(j));
      worst = std::max(worst, (hand.joints_world[j] - truth.world_from_hand * pose.position_m[j]).norm());
    }
  }
  EXPECT_LT(worst, 1e-6) << "noise-free stars give every joint exactly";
}

TEST(HandLayout, TheShippedHandStarsShareNoFaceWithEachOtherOrAnyObjectStar) {
  const auto objects = load_star_set(fs::path(RHOT_ASSET_DIR) / "stars" / "seed-case.json");
  ASSERT_TRUE(objects.has_value());
  const std::array<HandLayout, 2> hands{shipped_layout("low-cost-left"), shipped_layout("low-cost-right")};
  EXPECT_EQ(check_hand_stars(hands, *objects), std::vector<std::string>{});
  EXPECT_EQ(check_hand_stars({hands[0], shipped_layout("high-fidelity-right")}, *objects), std::vector<std::string>{});
}

// The right hand's layout mirrored in x, as the shipped left hand once was.
HandLayout mirrored_left(HandLayout layout) {
  layout.side = HandSide::kLeft;
  for (std::size_t m = 0; m < layout.hand_frame_markers; ++m) layout.markers[m].offset_m.x() *= -1.0;
  return layout;
}

TEST(HandLayout, AMirroredHandStarClashesWithTheOtherHandInEveryFace) {
  const HandLayout right = low_cost();
  const auto problems = check_hand_stars({mirrored_left(right), right}, StarSet{});
  ASSERT_EQ(problems.size(), 4U) << "each face matches its mirror image, and nothing else";
  EXPECT_EQ(problems[0], "left hand star (low-cost) face 0 and right hand star (low-cost) face 0 differ by at most 0 mm in every edge");
}

// Two hands pinching, the right one passing over the left (4 cm above it), seen with noise and
// each marker missing in 30 % of frames. Frames in which a hand is reported where the other hand
// is (hand_confused), with the hand stars followed by one shared StarTracker or by one each.
int confusion_frames(const std::array<HandLayout, 2>& layouts, bool shared, unsigned seed) {
  std::array<HandPose, 2> skeleton;
  std::array<std::array<FingerChain, kFingerCount>, 2> chains;
  std::array<std::array<FingerAngles, kFingerCount>, 2> relaxed;
  std::vector<HandTracker> own;
  for (std::size_t h = 0; h < 2; ++h) {
    skeleton[h] = reference_open_hand(layouts[h].side);
    chains[h] = hand_chains(skeleton[h], layouts[h].side);
    relaxed[h] = HandSolver(layouts[h].side, skeleton[h]).state().angles;
    // Trackers alone cannot tell whose markers a point near a hidden star's hand is: the frame from
    // the markers (HandTrackerSettings::frame_from_markers) is for hands tracked together.
    HandTrackerSettings settings;
    settings.frame_from_markers = shared ? HandTrackerSettings::MarkerFrame::kOn : HandTrackerSettings::MarkerFrame::kOff;
    own.emplace_back(layouts[h], skeleton[h], settings);
  }
  StarSet both;
  for (const HandLayout& l : layouts) both.stars.push_back(l.hand_star_set().stars[0]);
  both.stars[1].id = 1;
  StarTracker stars{StarLibrary(both)};
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, 0.0004);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  int confused = 0;
  for (int f = 0; f < 360; ++f) {
    const double t = f / 90.0;
    const double across = -0.15 + 0.30 * std::min(1.0, t / 3.0);  // the right hand from x = +0.15 m to -0.15 m
    std::array<Eigen::Vector3d, 2> wrist;
    std::vector<Eigen::Vector3d> points;
    for (std::size_t h = 0; h < 2; ++h) {
      const Eigen::Vector3d centre = h == 0 ? Eigen::Vector3d(0.0, 1.0, -0.45) : Eigen::Vector3d(-across, 1.04, -0.45);
      const HandMotionFrame truth = *hand_motion("pinch", t + 0.7 * static_cast<double>(h), chains[h], relaxed[h], centre);
      const HandPose pose = hand_pose_from_angles(skeleton[h], chains[h], truth.angles);
      wrist[h] = truth.world_from_hand * pose.position_m[static_cast<std::size_t>(HandJoint::kWrist)];
      for (const Eigen::Vector3d& m : markers(layouts[h], truth.world_from_hand, pose)) {
        if (uniform(rng) < 0.3) continue;
        points.push_back(m + Eigen::Vector3d{noise(rng), noise(rng), noise(rng)});
      }
    }
    std::shuffle(points.begin(), points.end(), rng);
    if (shared) {
      std::vector<bool> taken;
      const std::array<HandTracker*, 2> hands{&own[0], &own[1]};
      const std::array<int, 2> star{0, 1};
      track_hands(hands, star, stars.update(t, points), t, points, {}, taken);
    } else {
      for (HandTracker& h : own) h.update(t, points);
    }
    for (std::size_t h = 0; h < 2; ++h) {
      const TrackedHand& hand = own[h].last();
      if (hand.hand_seen && hand_confused(hand.joints_world[static_cast<std::size_t>(HandJoint::kWrist)], wrist[h], wrist[1 - h])) {
        ++confused;
      }
    }
  }
  return confused;
}

TEST(HandTracker, TwoHandsPassingEachOtherAreNeverConfused) {
  const std::array<HandLayout, 2> shipped{shipped_layout("low-cost-left"), low_cost()};
  for (const unsigned seed : {1U, 2U, 3U}) {
    EXPECT_EQ(confusion_frames(shipped, true, seed), 0) << "seed " << seed;
    EXPECT_EQ(confusion_frames(shipped, false, seed), 0) << "seed " << seed << ": the stars alone tell the hands apart";
  }
}

TEST(HandTracker, AMirroredLeftHandStarIsTakenForTheRightHand) {
  // The failure the shipped layouts fix: a face of the mirrored star is a face of the other's.
  // (The star tracker's pose filter refuses some of it, not all: over three seeds it happens.)
  const std::array<HandLayout, 2> mirrored{mirrored_left(low_cost()), low_cost()};
  int confused = 0;
  for (const unsigned seed : {1U, 2U, 3U}) confused += confusion_frames(mirrored, false, seed);
  EXPECT_GT(confused, 0);
}

// A scripted hand motion through the seated rig as `rhot-eval hands` runs it: the user's hand
// (`user`: the truth's bones) photographed with 0.5 px noise, its own bones hiding its markers,
// matched, triangulated and tracked with `skeleton`. Every seen fingertip's error (metres), sorted.
std::vector<double> fingertip_errors_through_cameras(const HandLayout& layout, const HandPose& skeleton, const HandPose& user,
                                                     const char* motion, unsigned seed, int frames = 300,
                                                     const HandTrackerSettings& tracker_settings = {}) {
  auto rig = load_rig(fs::path(RHOT_ASSET_DIR) / "rigs" / "seated-4.yaml");
  EXPECT_TRUE(rig.has_value());
  if (!rig) return {};
  const HandPose reference = reference_open_hand(layout.side);
  const auto chains = hand_chains(reference, layout.side);
  const auto user_chains = hand_chains(user, layout.side);
  const auto relaxed = HandSolver(layout.side, reference).state().angles;
  const Eigen::Vector3d centre(0.0, 1.1, -0.45);
  auto truth_at = [&](double t) {
    const HandMotionFrame m = *hand_motion(motion, t, chains, relaxed, centre);
    return std::make_pair(m.world_from_hand, hand_pose_from_angles(user, user_chains, m.angles));
  };
  SimulatedRigSettings settings;
  settings.sigma_px = 0.5;
  settings.seed = seed;
  SimulatedRig sim(*rig, {}, settings);
  sim.set_scripted_markers([&](double t) {
    const auto [world_from_hand, pose] = truth_at(t);
    return layout_markers(layout, world_from_hand, pose);
  });
  HandTracker tracker(layout, skeleton, tracker_settings);
  PixelSigmaEstimate pixel_sigma;
  std::vector<double> errors;
  for (int f = 0; f < frames; ++f) {
    const double t = f / settings.rate_hz;
    const auto [world_from_hand, pose] = truth_at(t);
    sim.set_occluders(hand_bone_occluders(world_from_hand, pose));
    const RigFrame frame = sim.next();
    const auto matched = match_and_triangulate(*rig, frame, match_settings_for(pixel_sigma.sigma_px()));
    std::vector<Eigen::Vector3d> points;
    for (const MatchedPoint& m : matched) points.push_back(m.point.position_world);
    const TrackedHand& hand = tracker.update(frame.time_s, points, point_sigmas_m(matched, pixel_sigma.update(matched)));
    if (!hand.hand_seen) continue;
    for (int k = 0; k < kFingerCount; ++k) {
      if (!hand.state.tip_seen[static_cast<std::size_t>(k)]) continue;
      const auto tip = static_cast<std::size_t>(chain_joints(static_cast<Finger>(k))[3]);
      errors.push_back((hand.joints_world[tip] - world_from_hand * pose.position_m[tip]).norm());
    }
  }
  std::sort(errors.begin(), errors.end());
  return errors;
}

double p95(const std::vector<double>& sorted) { return sorted.empty() ? 1e9 : sorted[sorted.size() * 95 / 100]; }

TEST(HandTracker, AGhostPointNeverLeavesAFingertipOnAnotherFingersMarker) {
  // Seeds 1 and 2 of a pinch: as the index closes on the thumb, the matching makes two ghosts for
  // a frame, one 29 mm from the hidden index marker. With a 40 mm fingertip gate the index took
  // it, and the index and middle fingers then held each other's markers for the rest of the run
  // (p95 69 mm). A tight gate, widening only while a fingertip has lost its marker, keeps them.
  const HandPose skeleton = reference_open_hand(HandSide::kRight);
  for (const unsigned seed : {1U, 2U, 3U}) {
    const auto errors = fingertip_errors_through_cameras(low_cost(), skeleton, skeleton, "pinch", seed);
    ASSERT_GT(errors.size(), 1000U) << "seed " << seed;
    EXPECT_LT(p95(errors), 0.006) << "seed " << seed;
  }
}

TEST(HandCalibration, AUsersLongerOrShorterFingersAreMeasuredFromAFlatHandThroughTheCameras) {
  // A user's hand with its own bones (independent_hand: within about +-10 %), held flat for a
  // second where the motion starts, as `rhot-eval hands --calibrate-hand` does; then tracked with
  // the reference skeleton and with the calibrated one.
  const HandLayout layout = low_cost();
  const HandPose reference = reference_open_hand(HandSide::kRight);
  for (const unsigned seed : {1U, 2U}) {
    const HandPose user = independent_hand(reference, seed);
    const auto chains = hand_chains(reference, HandSide::kRight);
    const auto relaxed = HandSolver(HandSide::kRight, reference).state().angles;
    const Rigid3d world_from_hand = hand_motion("open", 0.0, chains, relaxed, {0.0, 1.1, -0.45})->world_from_hand;
    const HandPose flat = hand_pose_from_angles(user, hand_chains(user, HandSide::kRight), {});
    auto rig = load_rig(fs::path(RHOT_ASSET_DIR) / "rigs" / "seated-4.yaml");
    ASSERT_TRUE(rig.has_value());
    SimulatedRigSettings settings;
    settings.sigma_px = 0.5;
    settings.seed = seed;
    SimulatedRig sim(*rig, {}, settings);
    const auto flat_markers = layout_markers(layout, world_from_hand, flat);
    sim.set_scripted_markers([&](double) { return flat_markers; });
    HandTracker tracker(layout, reference);
    std::vector<FingertipSample> samples;
    for (int f = 0; f < 90; ++f) {
      const RigFrame frame = sim.next();
      std::vector<Eigen::Vector3d> points;
      for (const MatchedPoint& m : match_and_triangulate(*rig, frame, match_settings_for(0.5))) points.push_back(m.point.position_world);
      samples.push_back(flat_hand_sample(layout, reference, tracker.update(frame.time_s, points), points));
    }
    const auto calibrated = calibrate_flat_hand(reference, HandSide::kRight, samples);
    ASSERT_TRUE(calibrated.has_value());
    const auto user_chains = hand_chains(user, HandSide::kRight);
    const auto calibrated_chains = hand_chains(*calibrated, HandSide::kRight);
    for (std::size_t f = 0; f < kFingerCount; ++f) {
      // Root to tip: the user's finger from the reference knuckle, as the calibration sees it.
      const double truth = (finger_forward(user_chains[f], {})[3] - chains[f].root_m).norm();
      const double measured = calibrated_chains[f].length_m[0] + calibrated_chains[f].length_m[1] + calibrated_chains[f].length_m[2];
      EXPECT_NEAR(measured, truth, 0.0015) << "seed " << seed << " finger " << f;
    }
    const auto before = fingertip_errors_through_cameras(layout, reference, user, "open", seed, 180);
    HandTrackerSettings calibrated_settings;
    calibrated_settings.finger_length_tolerance = 0.0;  // the skeleton is the user's (rhot-eval hands --calibrate-hand)
    const auto after = fingertip_errors_through_cameras(layout, *calibrated, user, "open", seed, 180, calibrated_settings);
    EXPECT_LT(p95(after), 0.005) << "seed " << seed;
    EXPECT_LT(p95(after), p95(before)) << "seed " << seed;
  }
}

}  // namespace
}  // namespace rhot

namespace rhot {
namespace {

// A user's glove hand whose fingers are 20 % longer than the reference's and whose index and ring
// knuckles sit elsewhere, closing and opening; the seen tip markers through the tracker (labelled,
// 3-6 s), with the reference skeleton and with the one calibrated from the first 3 s.
TEST(HandCalibration, ALabelledTakesFirstSecondsGiveEachFingersKnuckleAndLength) {
  const HandLayout layout = shipped_layout("glove-13-right");
  const HandPose reference = reference_open_hand(HandSide::kRight);
  HandPose user = reference;
  for (int f = 0; f < kFingerCount; ++f) {
    const auto joints = chain_joints(static_cast<Finger>(f));
    const Eigen::Vector3d root = reference.position_m[static_cast<std::size_t>(joints[0])];
    for (std::size_t k = 1; k < 4; ++k) {
      auto& p = user.position_m[static_cast<std::size_t>(joints[k])];
      p = root + 1.2 * (p - root);
    }
  }
  const std::array<std::pair<Finger, Eigen::Vector3d>, 2> moved{
      {{Finger::kIndex, {0.005, 0.0, -0.008}}, {Finger::kRing, {-0.004, 0.0, 0.006}}}};
  for (const auto& [finger, by] : moved) {
    const auto joints = chain_joints(finger);
    for (const HandJoint j : joints) user.position_m[static_cast<std::size_t>(j)] += by;
    user.position_m[static_cast<std::size_t>(joints[0]) - 1] += by;  // the metacarpal's base
  }
  const auto chains = hand_chains(reference, HandSide::kRight), user_chains = hand_chains(user, HandSide::kRight);
  const auto relaxed = HandSolver(HandSide::kRight, reference).state().angles;
  std::vector<std::vector<Eigen::Vector3d>> frames;
  for (int f = 0; f < 540; ++f) {
    const HandMotionFrame truth = *hand_motion("power-grasp", f / 90.0, chains, relaxed, {0.0, 1.1, -0.45});
    frames.push_back(markers(layout, truth.world_from_hand, hand_pose_from_angles(user, user_chains, truth.angles)));
  }
  LabelledCalibration report;
  const auto calibrated = calibrate_from_labelled(layout, reference, std::span(frames).first(270), &report);
  ASSERT_TRUE(calibrated.has_value());
  EXPECT_EQ(report.frames, 270);
  const auto seen_tip_error_mm = [&](const HandPose& skeleton) {
    HandTracker tracker(layout, skeleton);
    double sum = 0.0;
    int n = 0;
    for (std::size_t f = 0; f < frames.size(); ++f) {
      const TrackedHand& hand = tracker.update_labelled(static_cast<double>(f) / 90.0, frames[f]);
      if (f < 270) continue;
      const auto estimated = tracker.markers_in_hand();
      for (std::size_t m = 3; m < 8; ++m, ++n) sum += 1e3 * (hand.world_from_hand * estimated[m] - frames[f][m]).norm();
    }
    return sum / n;
  };
  const double before = seen_tip_error_mm(reference), after = seen_tip_error_mm(*calibrated);
  ::testing::Test::RecordProperty("seen_tip_before_mm", std::to_string(before));
  ::testing::Test::RecordProperty("seen_tip_after_mm", std::to_string(after));
  for (const auto& [finger, by] : moved) {
    const auto f = static_cast<std::size_t>(finger);
    ::testing::Test::RecordProperty("finger" + std::to_string(f) + "_rms_mm", std::to_string(1e3 * report.reach_rms_m[f][0]) + " -> " +
                                                                                  std::to_string(1e3 * report.reach_rms_m[f][1]));
  }
  SCOPED_TRACE(::testing::Message() << "seen tip markers " << before << " mm with the reference hand, " << after << " mm calibrated");
  // Measured: 12.1 mm with the reference hand, 1.2 mm calibrated; the fingers' markers' RMS miss
  // (the tip's weighing four times a middle marker's) 6.9 -> 3.8 and 6.3 -> 3.3 mm. Knuckle, length
  // and direction trade for each other (the truth's last hinges are not the IK's coupling, and the
  // middle markers' offsets are fitted too), so the knuckle found serves the IK rather than being
  // the true one: what is asserted is what the tracker shows.
  EXPECT_LT(after, 3.0);
  EXPECT_LT(after, 0.25 * before);
  for (const auto& [finger, by] : moved) {
    const auto f = static_cast<std::size_t>(finger);
    EXPECT_LT(report.reach_rms_m[f][1], 0.6 * report.reach_rms_m[f][0]) << "finger " << f;
  }
}

TEST(HandCalibration, AFlatHandGivesEachFingersLengthAndTheFileKeepsIt) {
  const HandPose reference = reference_open_hand(HandSide::kRight);
  const auto chains = hand_chains(reference, HandSide::kRight);
  // A user whose fingers are 10 % longer (index), 8 % shorter (little), the rest as the reference.
  const std::array<double, kFingerCount> scale{1.0, 1.1, 1.0, 1.0, 0.92};
  std::vector<FingertipSample> samples;
  for (int s = 0; s < 30; ++s) {
    FingertipSample sample;
    for (int f = 0; f < kFingerCount; ++f) {
      FingerChain c = chains[static_cast<std::size_t>(f)];
      for (double& l : c.length_m) l *= scale[static_cast<std::size_t>(f)];
      sample[static_cast<std::size_t>(f)] = finger_forward(c, FingerAngles{})[3] + Eigen::Vector3d(0.0002 * (s % 3 - 1), 0.0, 0.0);
    }
    samples.push_back(sample);
  }
  const auto calibrated = calibrate_flat_hand(reference, HandSide::kRight, samples);
  ASSERT_TRUE(calibrated.has_value());
  const auto calibrated_chains = hand_chains(*calibrated, HandSide::kRight);
  for (int f = 0; f < kFingerCount; ++f) {
    for (std::size_t k = 0; k < 3; ++k) {
      EXPECT_NEAR(calibrated_chains[static_cast<std::size_t>(f)].length_m[k],
                  scale[static_cast<std::size_t>(f)] * chains[static_cast<std::size_t>(f)].length_m[k], 2e-4)
          << "finger " << f << " bone " << k;
    }
  }
  const fs::path file = fs::path(::testing::TempDir()) / "rhot_hand_calibration.json";
  ASSERT_TRUE(save_hand_calibration(*calibrated, HandSide::kRight, file).has_value());
  const auto back = load_hand_calibration(file);
  ASSERT_TRUE(back.has_value()) << back.error();
  EXPECT_EQ(back->second, HandSide::kRight);
  for (int j = 0; j < kHandJointCount; ++j) {
    EXPECT_LT((back->first.position_m[static_cast<std::size_t>(j)] - calibrated->position_m[static_cast<std::size_t>(j)]).norm(), 1e-9);
  }
  std::ofstream(file) << R"({"format": "rhot-hand-calibration", "version": 1, "side": "right", "joints_mm": {}, "radii_mm": {}})";
  EXPECT_EQ(load_hand_calibration(file).error(), file.string() + ": /joints_mm: missing required key \"palm\"");
  std::ofstream(file)
      << R"({"format": "rhot-hand-calibration", "version": 1, "side": "right", "joints_mm": {"palm": [0, 1]}, "radii_mm": {}})";
  EXPECT_EQ(load_hand_calibration(file).error(), file.string() + ": /joints_mm/palm: expected an array of 3 numbers, got an array of 2");
  EXPECT_FALSE(calibrate_flat_hand(reference, HandSide::kRight, {}).has_value());
}

}  // namespace
}  // namespace rhot

namespace rhot {
namespace {

TEST(HandLayout, TheColourLayoutsNameEveryFingertipByItsColour) {
  for (const char* name : {"colour-right", "colour-left"}) {
    const HandLayout layout = shipped_layout(name);
    EXPECT_EQ(marker_colour_name(layout.hand_star_colour()), "blue") << name;
    const std::array<std::string_view, 5> tips{"red", "yellow", "green", "cyan", "magenta"};
    for (int f = 0; f < 5; ++f) EXPECT_EQ(marker_colour_name(layout.fingertip_colour(f)), tips[static_cast<std::size_t>(f)]) << name;
    EXPECT_EQ(layout_marker_colours(layout), (std::vector<int>{5, 5, 5, 5, 0, 2, 3, 4, 7})) << name;
  }
  EXPECT_EQ(layout_error(R"({"format": "rhot-hand-layout", "version": 1, "side": "right", "marker_diameter_mm": 14,
      "hand_star_mm": [[0,0,0],[10,0,0],[0,20,0],[0,0,30]], "fingertip_markers": {"index_tip": 8},
      "marker_colours": {"index_tip": "teal"}})"),
            "/marker_colours/index_tip: expected a marker colour (red, orange, yellow, green, cyan, blue, purple, magenta), got "
            "\"teal\"");
  EXPECT_EQ(layout_error(R"({"format": "rhot-hand-layout", "version": 1, "side": "right", "marker_diameter_mm": 14,
      "hand_star_mm": [[0,0,0],[10,0,0],[0,20,0],[0,0,30]], "fingertip_markers": {"index_tip": 8},
      "marker_colours": {"thumb_tip": "red"}})"),
            "/marker_colours/thumb_tip: a colour for a fingertip without a marker (add it to \"fingertip_markers\")");
}

TEST(HandLayout, MarkersOnBonesAreCheckedWithExactErrors) {
  const std::string head = R"("format": "rhot-hand-layout", "version": 1, "side": "right", "marker_diameter_mm": 6)";
  const std::string back = R"({"name": "a", "bone": "wrist", "offset_mm": [0, 18, -80]},
      {"name": "b", "bone": "wrist", "offset_mm": [-27, 18, -35]}, {"name": "c", "bone": "wrist", "offset_mm": [6, 18, -35]})";
  const auto with = [&](const std::string& more) { return "{" + head + R"(, "markers": [)" + back + more + "]}"; };
  EXPECT_EQ(layout_error(with("")), "loaded");
  EXPECT_EQ(layout_error(with(R"(, {"name": "tip", "bone": "index_distal", "offset_mm": [0, 9, -10], "colour": "red"})")), "loaded");
  EXPECT_EQ(layout_error("{" + head + R"(, "markers": [{"name": "a", "bone": "wrist", "offset_mm": [0, 18, -80]}]})"),
            "/markers: expected three or four markers on \"wrist\" (the back of the hand, which gives the hand its frame), got 1");
  EXPECT_EQ(layout_error(with(R"(, {"name": "a", "bone": "index_tip", "offset_mm": [0, 0, -8]})")),
            "/markers/3/name: \"a\" names marker 0 already");
  EXPECT_EQ(layout_error(with(R"(, {"name": "d", "bone": "index_knuckle", "offset_mm": [0, 0, -8]})")),
            "/markers/3/bone: expected a joint (wrist, thumb_metacarpal, thumb_proximal, thumb_distal, thumb_tip, index_proximal, "
            "index_intermediate, index_distal, index_tip, middle_proximal, middle_intermediate, middle_distal, middle_tip, "
            "ring_proximal, ring_intermediate, ring_distal, ring_tip, little_proximal, little_intermediate, little_distal, little_tip), "
            "got \"index_knuckle\"");
  EXPECT_EQ(layout_error(with(R"(, {"name": "d", "bone": "ring_metacarpal", "offset_mm": [0, 15, -40]})")),
            "/markers/3/bone: \"ring_metacarpal\" moves with the hand: give the back of the hand's markers on \"wrist\"");
  EXPECT_EQ(layout_error(with(R"(, {"name": "d", "bone": "index_tip", "offset_mm": [0, 0, -151]})")),
            "/markers/3/offset_mm: expected each coordinate within 150 mm of the joint");
  EXPECT_EQ(layout_error(with(R"(, {"name": "d", "bone": "index_tip", "offset_mm": [0, 0]})")),
            "/markers/3/offset_mm: expected an array of 3 numbers, got an array of 2");
  EXPECT_EQ(layout_error(with(R"(, {"name": "d", "bone": "index_tip", "offset_mm": [0, 0, -8], "colour": "teal"})")),
            "/markers/3/colour: expected a marker colour (red, orange, yellow, green, cyan, blue, purple, magenta), got \"teal\"");
  EXPECT_EQ(layout_error(with(R"(, {"name": "d", "bone": "index_tip", "offset_mm": [0, 0, -8]},
                                  {"name": "e", "bone": "index_distal", "offset_mm": [0, 9, -10]})")),
            "/markers: \"e\" and \"d\" are both on the last bone of a finger, whose one marker there is its fingertip marker");
  EXPECT_EQ(layout_error("{" + head + R"(, "markers": [{"name": "a", "bone": "wrist", "offset_mm": [0, 18, -80]},
      {"name": "b", "bone": "wrist", "offset_mm": [0, 18, -35]}, {"name": "c", "bone": "wrist", "offset_mm": [2, 18, -55]}]})"),
            "/markers: the back of the hand's markers \"a\", \"b\" and \"c\" are nearly in a line (each must be 5 mm off the line "
            "through the others)");
  // An isosceles back: its two equal edges would let the cameras take one marker for the other.
  EXPECT_EQ(layout_error("{" + head + R"(, "markers": [{"name": "a", "bone": "wrist", "offset_mm": [0, 18, -80]},
      {"name": "b", "bone": "wrist", "offset_mm": [-20, 18, -35]}, {"name": "c", "bone": "wrist", "offset_mm": [20, 18, -35]}]})"),
            "/markers: the back of the hand's three markers make a triangle with two edges within 3 mm of each other (49, 40 and 49 mm): "
            "through cameras its markers cannot be told apart");
  EXPECT_EQ(layout_error("{" + head + R"(, "markers": [{"name": "a", "bone": "wrist", "offset_mm": [0, 18, -80], "colour": "blue"},
      {"name": "b", "bone": "wrist", "offset_mm": [-27, 18, -35]}, {"name": "c", "bone": "wrist", "offset_mm": [6, 18, -35]}]})"),
            "/markers: the back of the hand's markers share one colour: \"b\" differs from \"a\"");
  EXPECT_EQ(layout_error("{" + head + R"(, "markers": [], "hand_star_mm": [[0, 0, 0]]})"),
            "/hand_star_mm: a layout with \"markers\" gives every marker there (with its \"colour\")");
  EXPECT_EQ(layout_error("{" + head + R"(, "markers": [{"name": "a", "bone": "wrist", "offset_mm": [0, 0, 0]},
      {"name": "b", "bone": "wrist", "offset_mm": [10, 0, 0]}, {"name": "c", "bone": "wrist", "offset_mm": [0, 10, 0]},
      {"name": "d", "bone": "wrist", "offset_mm": [0, 0, 30]}]})"),
            "/markers: edges 10 and 10 mm differ by less than 1.5 mm");
}

// The earlier form ("hand_star_mm", "fingertip_markers", "marker_colours") reads as the same
// markers as the shipped layouts' lists.
TEST(HandLayout, TheEarlierFormIsTheSameLayout) {
  const std::string earlier = R"({"format": "rhot-hand-layout", "version": 1, "name": "colour", "side": "right", "marker_diameter_mm": 14,
    "hand_star_mm": [[-5.0, 12.3, -71.6], [17.9, 15.0, -69.0], [13.5, 14.9, -34.2], [-13.3, 14.7, -23.3]],
    "fingertip_markers": {"thumb_tip": 10, "index_tip": 10, "middle_tip": 10, "ring_tip": 10, "little_tip": 10},
    "marker_colours": {"hand_star": "blue", "thumb_tip": "red", "index_tip": "yellow", "middle_tip": "green", "ring_tip": "cyan",
                       "little_tip": "magenta"}})";
  const fs::path file = fs::path(::testing::TempDir()) / "rhot_earlier_layout.json";
  std::ofstream(file) << earlier;
  const auto read = load_hand_layout(file);
  ASSERT_TRUE(read.has_value()) << read.error();
  const HandLayout shipped = shipped_layout("colour-right");
  const HandPose pose = reference_open_hand(HandSide::kRight);
  const Rigid3d at{Eigen::Quaterniond(Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitY())), {0.1, 1.0, -0.3}};
  const auto a = layout_markers(*read, at, pose), b = layout_markers(shipped, at, pose);
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t m = 0; m < a.size(); ++m) EXPECT_LT((a[m] - b[m]).norm(), 1e-12) << m;
  EXPECT_EQ(layout_marker_colours(*read), layout_marker_colours(shipped));
  EXPECT_EQ(layout_marker_names(*read), layout_marker_names(shipped));
  // A fingertip marker "d mm beyond the tip" sits d mm beyond the tip along the distal bone.
  const auto tip = static_cast<std::size_t>(HandJoint::kIndexTip), distal = static_cast<std::size_t>(HandJoint::kIndexDistal);
  const Eigen::Vector3d along = (pose.position_m[tip] - pose.position_m[distal]).normalized();
  EXPECT_LT((a[5] - at * (pose.position_m[tip] + 0.010 * along)).norm(), 1e-12);
}

TEST(HandLayout, TheGloveLayoutNamesTheMarkersOfARealGlove) {
  const HandLayout right = shipped_layout("glove-13-right"), left = shipped_layout("glove-13-left");
  EXPECT_EQ(right.hand_frame_markers, 3U);
  EXPECT_FALSE(right.has_hand_star());
  EXPECT_EQ(camera_hand_star_problem(right),
            "the layout \"glove-13\" has 3 markers on the back of the hand; the runtime follows hands through cameras by a marker star "
            "of four: this layout serves takes and rhot-eval's single hands only");
  // The shared take's names (../shared/data/glove-take), back of the hand and fingertips first.
  EXPECT_EQ(layout_marker_names(right),
            (std::vector<std::string>{"hand_top", "hand_left", "hand_right", "thumb_tip", "index_tip", "middle_tip", "ring_tip",
                                      "little_tip", "thumb_middle", "index_middle", "middle_middle", "ring_middle", "little_middle"}));
  EXPECT_EQ(layout_marker_names(left), layout_marker_names(right));
  // Each finger's two markers on the reference hand as far apart as on the take's glove (the
  // median over its 30 s) within 10 mm, and the left glove the right's mirror image.
  const HandPose pose_right = reference_open_hand(HandSide::kRight), pose_left = reference_open_hand(HandSide::kLeft);
  const auto r = layout_markers(right, Rigid3d{}, pose_right), l = layout_markers(left, Rigid3d{}, pose_left);
  const std::array<double, 5> take_mm{32.7, 61.0, 66.2, 60.0, 38.6};
  for (std::size_t f = 0; f < 5; ++f) EXPECT_NEAR(1000.0 * (r[3 + f] - r[8 + f]).norm(), take_mm[f], 10.0) << f;
  EXPECT_NEAR(1000.0 * (r[0] - r[1]).norm(), 55.2, 0.1);
  EXPECT_NEAR(1000.0 * (r[0] - r[2]).norm(), 44.8, 0.1);
  EXPECT_NEAR(1000.0 * (r[1] - r[2]).norm(), 32.4, 0.1);
  for (std::size_t m = 0; m < r.size(); ++m) EXPECT_LT((l[m] - Eigen::Vector3d(-r[m].x(), r[m].y(), r[m].z())).norm(), 1e-9) << m;
}

// A glove hand (three markers on its back, a tip and a middle marker per finger) from its labelled
// markers, each fingertip hidden in turn for 0.5 s after 4 s seen; the hidden tip markers' mean
// error, with and without the fingertip model (which uses the finger's own middle marker too).
struct LabelledRun {
  double seen_worst_mm = 0.0, seen_mean_mm = 0.0, hidden_mean_mm = 0.0;
  int hidden_frames = 0, model_frames = 0;
};
LabelledRun glove_labelled_run(bool fingertip_model, unsigned seed) {
  const HandLayout layout = shipped_layout("glove-13-right");
  const HandPose skeleton = reference_open_hand(HandSide::kRight);
  const auto chains = hand_chains(skeleton, HandSide::kRight);
  const auto relaxed = HandSolver(HandSide::kRight, skeleton).state().angles;
  HandTrackerSettings settings;
  settings.fingertip_model = fingertip_model;
  HandTracker tracker(layout, skeleton, settings);
  LabelledRun run;
  double sum = 0.0, seen_sum = 0.0;
  int seen_count = 0;
  for (int f = 0; f < 1260; ++f) {
    const double t = f / 90.0;
    const HandMotionFrame truth = *hand_motion("power-grasp", t, chains, relaxed, {0.0, 1.1, -0.45});
    const HandPose pose = hand_pose_from_angles(skeleton, chains, independent_angles(truth.angles, seed));
    const std::vector<Eigen::Vector3d> true_markers = markers(layout, truth.world_from_hand, pose);
    std::vector<Eigen::Vector3d> labelled = true_markers;
    const int gap = f >= 360 ? (f - 360) / 45 : -1;
    const int hidden = gap >= 0 && gap % 2 == 0 ? layout.fingertip_marker[static_cast<std::size_t>(gap / 2 % kFingerCount)] : -1;
    if (hidden >= 0) labelled[static_cast<std::size_t>(hidden)] = Eigen::Vector3d::Constant(std::nan(""));
    const TrackedHand& hand = tracker.update_labelled(t, labelled);
    EXPECT_TRUE(hand.hand_seen) << f;
    const auto estimated = tracker.markers_in_hand();
    for (std::size_t m = 3; m < 8; ++m) {
      const double e = 1000.0 * (hand.world_from_hand * estimated[m] - true_markers[m]).norm();
      if (static_cast<int>(m) == hidden) {
        sum += e;
        ++run.hidden_frames;
      } else if (f >= 10) {
        run.seen_worst_mm = std::max(run.seen_worst_mm, e);
        seen_sum += e;
        ++seen_count;
      }
    }
  }
  run.hidden_mean_mm = sum / std::max(run.hidden_frames, 1);
  run.seen_mean_mm = seen_sum / std::max(seen_count, 1);
  run.model_frames = tracker.fingertip_model_frames();
  return run;
}

TEST(HandTracker, AGloveFromLabelledMarkersPlacesAHiddenTipByItsOwnMiddleMarkerAndTheOthers) {
  for (const unsigned seed : {1u, 2u}) {
    const LabelledRun model = glove_labelled_run(true, seed), rule = glove_labelled_run(false, seed);
    SCOPED_TRACE(::testing::Message() << "seed " << seed << ": hidden tips " << model.hidden_mean_mm << " mm mean with the model, "
                                      << rule.hidden_mean_mm << " by the rule; seen tips " << model.seen_mean_mm << " mm mean, "
                                      << model.seen_worst_mm << " mm at most");
    EXPECT_GT(model.hidden_frames, 300);
    EXPECT_GE(model.model_frames, HandTracker::kFingertipModelFrames);
    // Measured: seen 0.54 and 0.52 mm mean, 4.9 and 5.0 mm at most (the fingers' IK reaches for the
    // tip alone, with the last hinge coupled: a nail marker 10 mm off the bone's axis shows the
    // distal bone's angle); hidden 0.79 and 0.62 mm with the model, 6.7 and 6.4 mm by the rule.
    EXPECT_LT(model.seen_mean_mm, 1.0) << "labelled, noise-free markers on the tracker's own skeleton";
    EXPECT_LT(model.seen_worst_mm, 8.0);
    EXPECT_LT(model.hidden_mean_mm, 2.0);
    EXPECT_LT(model.hidden_mean_mm, 0.3 * rule.hidden_mean_mm);
  }
  // Three markers on the back: no star to follow through cameras, so unlabelled points give no hand.
  HandTracker tracker(shipped_layout("glove-13-right"), reference_open_hand(HandSide::kRight));
  const std::vector<Eigen::Vector3d> points = markers(
      shipped_layout("glove-13-right"), Rigid3d{Eigen::Quaterniond::Identity(), {0.0, 1.1, -0.45}}, reference_open_hand(HandSide::kRight));
  EXPECT_FALSE(tracker.update(0.0, points).hand_seen);
  // Labelled markers with the back of the hand hidden, or not finite, or too few: no hand, nothing solved.
  std::vector<Eigen::Vector3d> bad = points;
  bad[1] = Eigen::Vector3d(std::numeric_limits<double>::infinity(), 0.0, 0.0);
  EXPECT_FALSE(tracker.update_labelled(0.1, bad).hand_seen);
  EXPECT_FALSE(tracker.update_labelled(0.2, std::span(points).first(2)).hand_seen);
  EXPECT_TRUE(tracker.update_labelled(0.3, points).hand_seen);
  for (const Eigen::Vector3d& j : tracker.last().joints_world) EXPECT_TRUE(j.allFinite());
  EXPECT_EQ(tracker.last().marker_point, (std::vector<int>{0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12})) << "every labelled marker used";
  // Among other hands and stars (LiveTracking), a hand without a star is never seen.
  HandTracker* const hand = &tracker;
  const int no_star = -1;
  std::vector<bool> taken;
  track_hands({&hand, 1}, {&no_star, 1}, {}, 0.4, points, {}, taken);
  EXPECT_FALSE(tracker.last().hand_seen);
}

// Neighbouring tips that took each other's points are exchanged back by their fingers' other
// markers (HandTracker::untangle_neighbours). The real glove take through the seated rig showed
// it: middle and ring fingers curled together, tips 15 mm apart, and once their predictions had
// crossed, nearest first kept the swap for up to 1.3 s (docs/tracking.md).
TEST(HandTracker, NeighbouringTipsThatTookEachOthersPointsAreExchangedBackByTheirMiddleMarkers) {
  const HandLayout glove = shipped_layout("glove-13-right");
  HandTracker tracker(glove, reference_open_hand(HandSide::kRight));
  // Middle and ring curled and leaning together.
  std::array<FingerAngles, kFingerCount> angles{};
  const auto middle = static_cast<std::size_t>(Finger::kMiddle), ring = static_cast<std::size_t>(Finger::kRing);
  for (std::size_t f = 0; f < kFingerCount; ++f) angles[f].flexion_rad = {0.3, 0.4, 0.25};
  angles[middle] = {0.15, {1.0, 1.2, 0.8}};
  angles[ring] = {-0.15, {1.0, 1.2, 0.8}};
  const HandPose pose = hand_pose_from_angles(reference_open_hand(HandSide::kRight), tracker.solver().chains(), angles);
  const Rigid3d world_from_hand{Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitY())), {0.05, 1.05, -0.4}};
  const std::vector<Eigen::Vector3d> points = markers(glove, world_from_hand, pose);
  for (int k = 0; k < 20; ++k) tracker.update_labelled(0.01 * k, points);
  const int middle_tip = glove.fingertip_marker[middle], ring_tip = glove.fingertip_marker[ring];
  ASSERT_LT((points[static_cast<std::size_t>(middle_tip)] - points[static_cast<std::size_t>(ring_tip)]).norm(), 0.025)
      << "the two tips crowd, as on the take";

  std::vector<int> right(glove.markers.size());
  for (std::size_t m = 0; m < right.size(); ++m) right[m] = m < glove.hand_frame_markers ? -1 : static_cast<int>(m);
  std::vector<int> swapped = right;
  std::swap(swapped[static_cast<std::size_t>(middle_tip)], swapped[static_cast<std::size_t>(ring_tip)]);
  tracker.begin(0.2, true, world_from_hand);
  std::vector<int> got = swapped;
  tracker.untangle_neighbours(points, got);
  EXPECT_EQ(got, right) << "the swap is put right";
  got = right;
  tracker.untangle_neighbours(points, got);
  EXPECT_EQ(got, right) << "the right assignment stays";
  // Without the middle markers nothing tells the two apart: the points stay where they were given.
  std::vector<int> no_middle = swapped;
  no_middle[static_cast<std::size_t>(glove.marker_index("middle_middle"))] = -1;
  got = no_middle;
  tracker.untangle_neighbours(points, got);
  EXPECT_EQ(got, no_middle);
  // A point that is not finite is never fitted.
  std::vector<Eigen::Vector3d> bad = points;
  bad[static_cast<std::size_t>(ring_tip)] = Eigen::Vector3d::Constant(std::nan(""));
  got = swapped;
  tracker.untangle_neighbours(bad, got);
  EXPECT_EQ(got, swapped);
}

// A fingertip whose layout gives it a colour takes only a point of that colour, and takes it at
// once wherever near the finger it reappears; without colours, the nearest point in the gate.
TEST(HandTracker, AColouredFingertipIsKnownByItsColourAlone) {
  const HandLayout layout = shipped_layout("colour-right");
  const HandPose skeleton = reference_open_hand(HandSide::kRight);
  const auto chains = hand_chains(skeleton, HandSide::kRight);
  const auto relaxed = HandSolver(HandSide::kRight, skeleton).state().angles;
  const HandMotionFrame truth = *hand_motion("pinch", 0.0, chains, relaxed, {0.0, 1.1, -0.45});
  const HandPose pose = hand_pose_from_angles(skeleton, chains, truth.angles);
  const std::vector<Eigen::Vector3d> points = markers(layout, truth.world_from_hand, pose);
  const std::vector<int> colours = layout_marker_colours(layout);
  constexpr std::size_t kIndex = 5;  // the index fingertip's marker (after the hand star and the thumb's)
  const int orange = *marker_colour_from_name("orange");
  for (const bool coloured : {true, false}) {
    HandTracker tracker(layout, skeleton);
    const auto update = [&](double t, const std::vector<Eigen::Vector3d>& p, const std::vector<int>& c) -> const TrackedHand& {
      return coloured ? tracker.update(t, p, {}, c) : tracker.update(t, p);
    };
    for (int f = 0; f < 30; ++f) ASSERT_EQ(update(f / 90.0, points, colours).fingertip_point[1], static_cast<int>(kIndex));
    // The index marker hidden; an orange point (no marker of this hand) 1 mm from where it was.
    std::vector<Eigen::Vector3d> decoy = points;
    std::vector<int> decoy_colours = colours;
    decoy.push_back(points[kIndex] + Eigen::Vector3d(0.001, 0.0, 0.0));
    decoy_colours.push_back(orange);
    decoy.erase(decoy.begin() + static_cast<std::ptrdiff_t>(kIndex));
    decoy_colours.erase(decoy_colours.begin() + static_cast<std::ptrdiff_t>(kIndex));
    const int taken = update(30 / 90.0, decoy, decoy_colours).fingertip_point[1];
    EXPECT_EQ(taken, coloured ? -1 : static_cast<int>(decoy.size()) - 1) << (coloured ? "coloured" : "uncoloured");
    // The index marker back, 3 cm from where it was: a coloured finger takes it in its first frame.
    std::vector<Eigen::Vector3d> moved = points;
    moved[kIndex] += Eigen::Vector3d(0.03, 0.0, 0.0);
    const int back = update(31 / 90.0, moved, colours).fingertip_point[1];
    EXPECT_EQ(back, coloured ? static_cast<int>(kIndex) : -1) << (coloured ? "coloured" : "uncoloured");
  }
}

// A hand turning its back away from the cameras (about its long axis, 60 degrees a second) while
// it moves: after 1 s seen whole, its star is hidden (all four markers, or all but one) for 1.5 s,
// its fingertip markers seen throughout. Its fingers hold their pose from then (a hand turning
// what it holds) or go on pinching. Where they hold, a point of the star's colour lies 15 mm from
// where the star's first marker is (a wrong point inside the gate: the fit must drop it, not
// follow it). The worst of the frames in which it is seen while its star is hidden.
struct TurnedAwayRun {
  int seen_frames = 0, seen_after_hold = 0, from_markers = 0, palm_fitted = 0, tips_measured = 0;
  double worst_frame_mm = 0.0, worst_angle_deg = 0.0, worst_tip_mm = 0.0;
};
TurnedAwayRun turn_the_back_away(const std::string& layout_name, HandTrackerSettings::MarkerFrame mode, int star_markers_left,
                                 bool fingers_move) {
  const HandLayout layout = shipped_layout(layout_name);
  const HandPose skeleton = reference_open_hand(HandSide::kRight);
  const auto chains = hand_chains(skeleton, HandSide::kRight);
  const auto relaxed = HandSolver(HandSide::kRight, skeleton).state().angles;
  HandTrackerSettings settings;
  settings.frame_from_markers = mode;
  settings.filter_frame = false;  // exact points: the frame is judged as fitted, not as smoothed (it would lag the turn)
  HandTracker tracker(layout, skeleton, settings);
  const std::vector<int> colours = layout_marker_colours(layout);
  const bool coloured = layout.markers.back().colour >= 0;
  const auto star_end = static_cast<std::ptrdiff_t>(layout.hand_frame_markers);
  TurnedAwayRun run;
  for (int f = 0; f < 225; ++f) {
    const double t = f / 90.0;
    const bool hidden = f >= 90;
    const HandMotionFrame truth = *hand_motion("pinch", t, chains, relaxed, {0.0, 1.1, -0.45});
    const HandMotionFrame fingers = fingers_move || !hidden ? truth : *hand_motion("pinch", 1.0, chains, relaxed, {0.0, 1.1, -0.45});
    const HandPose pose = hand_pose_from_angles(skeleton, chains, fingers.angles);
    Rigid3d world_from_hand = truth.world_from_hand;
    const double turn_rad = std::min(t, 1.5) * 60.0 * std::numbers::pi / 180.0;
    world_from_hand.rotation = (world_from_hand.rotation * Eigen::AngleAxisd(turn_rad, Eigen::Vector3d::UnitZ())).normalized();
    world_from_hand.translation += Eigen::Vector3d(0.1 * t, 0.0, 0.0);
    std::vector<Eigen::Vector3d> points = markers(layout, world_from_hand, pose);
    std::vector<int> point_colours = colours;
    if (hidden && !fingers_move) {
      points.push_back(points[0] + Eigen::Vector3d(0.015, 0.0, 0.0));
      point_colours.push_back(colours[0]);
    }
    if (hidden) {
      points.erase(points.begin() + star_markers_left, points.begin() + star_end);
      point_colours.erase(point_colours.begin() + star_markers_left, point_colours.begin() + star_end);
    }
    points.push_back({0.3, 1.0, -0.2});  // a stray marker
    point_colours.push_back(colours.back());
    const TrackedHand& hand = coloured ? tracker.update(t, points, {}, point_colours) : tracker.update(t, points);
    if (!hidden) {
      EXPECT_TRUE(hand.hand_seen) << f;
      EXPECT_EQ(hand.frame_source, HandFrameSource::kStar) << f;
      continue;
    }
    if (!hand.hand_seen) continue;
    if (t - 89.0 / 90.0 > HandTracker::kMarkerFrameHold_s + 1e-9) ++run.seen_after_hold;  // the star last seen in frame 89
    ++run.seen_frames;
    run.from_markers += hand.frame_source == HandFrameSource::kMarkers ? 1 : 0;
    // The palm fitted to the markers, not measured by the star; the seen tips still measured.
    run.palm_fitted += hand.state.confidence[static_cast<std::size_t>(HandJoint::kPalm)] == HandTracker::kMarkerFrameConfidence ? 1 : 0;
    run.tips_measured += hand.state.confidence[static_cast<std::size_t>(HandJoint::kIndexTip)] == 1.0 ? 1 : 0;
    run.worst_frame_mm = std::max(run.worst_frame_mm, 1000.0 * (hand.world_from_hand.translation - world_from_hand.translation).norm());
    run.worst_angle_deg =
        std::max(run.worst_angle_deg, hand.world_from_hand.rotation.angularDistance(world_from_hand.rotation) * 180.0 / std::numbers::pi);
    for (int k = 0; k < kFingerCount; ++k) {
      const auto tip = static_cast<std::size_t>(chain_joints(static_cast<Finger>(k))[3]);
      run.worst_tip_mm = std::max(run.worst_tip_mm, 1000.0 * (hand.joints_world[tip] - world_from_hand * pose.position_m[tip]).norm());
    }
  }
  return run;
}

TEST(HandTracker, AHandTurningItsBackAwayStaysSeenByItsFingertipsForASecondThenIsLost) {
  for (const std::string layout : {"low-cost-right", "colour-right"}) {
    for (const int left : {0, 1}) {
      SCOPED_TRACE(layout + ", star markers left " + std::to_string(left));
      using enum HandTrackerSettings::MarkerFrame;
      EXPECT_EQ(turn_the_back_away(layout, kOff, left, false).seen_frames, 0)
          << "without the frame from the markers, the hand is lost with its star";
      // Fingers held: seen for the hold (90 frames at 90 Hz) by its markers, not after, on the truth.
      const TurnedAwayRun held = turn_the_back_away(layout, kOn, left, false);
      EXPECT_EQ(held.seen_frames, 90);
      EXPECT_EQ(held.from_markers, held.seen_frames);
      EXPECT_EQ(held.palm_fitted, held.seen_frames);
      EXPECT_EQ(held.tips_measured, held.seen_frames);
      EXPECT_EQ(held.seen_after_hold, 0);
      EXPECT_LT(held.worst_frame_mm, 1.0);
      EXPECT_LT(held.worst_angle_deg, 0.5);
      EXPECT_LT(held.worst_tip_mm, 1.0);
      // Fingers pinching: the frame is fitted to the shape they had, so it is off by about as much as
      // they moved, and refused once a marker misses it by 6 mm (kMarkerFrameMiss_m). Seen for a
      // fifth of a second at least, never as far off as a finger.
      const TurnedAwayRun moving = turn_the_back_away(layout, kOn, left, true);
      EXPECT_GE(moving.seen_frames, 18);
      EXPECT_EQ(moving.seen_after_hold, 0);
      EXPECT_LT(moving.worst_frame_mm, 25.0);
      EXPECT_LT(moving.worst_angle_deg, 10.0);
      EXPECT_LT(moving.worst_tip_mm, 5.0);
    }
  }
}

TEST(HandTracker, TheFrameFromMarkersIsOnByDefaultWhereTheFingertipsAreKnownByTheirColour) {
  using enum HandTrackerSettings::MarkerFrame;
  EXPECT_EQ(turn_the_back_away("colour-right", kWhereColoured, 0, false).seen_frames, 90);
  EXPECT_EQ(turn_the_back_away("low-cost-right", kWhereColoured, 0, false).seen_frames, 0);
  EXPECT_EQ(HandTrackerSettings{}.frame_from_markers, kWhereColoured);
}

}  // namespace
}  // namespace rhot
