#include "tracking/hand/HandSolver.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>

namespace rhot {
namespace {

using Tips = std::array<std::optional<Eigen::Vector3d>, kFingerCount>;

Tips tips_of(const HandPose& pose) {
  Tips t;
  for (int f = 0; f < kFingerCount; ++f)
    t[static_cast<std::size_t>(f)] = pose.position_m[static_cast<std::size_t>(chain_joints(static_cast<Finger>(f))[3])];
  return t;
}

TEST(HandSolver, TheReferenceHandsTipsGiveBackItsTips) {
  for (const HandSide side : {HandSide::kLeft, HandSide::kRight}) {
    const HandPose reference = reference_open_hand(side);
    HandSolver solver(side, reference);
    const HandState& s = solver.update(0.0, tips_of(reference));
    for (int f = 0; f < kFingerCount; ++f) {
      const auto tip = static_cast<std::size_t>(chain_joints(static_cast<Finger>(f))[3]);
      EXPECT_LT((s.pose.position_m[tip] - reference.position_m[tip]).norm(), 0.0005) << "finger " << f;
      EXPECT_EQ(s.confidence[tip], 1.0);
    }
    for (int j = 0; j < kHandJointCount; ++j) {
      EXPECT_TRUE(s.pose.position_m[static_cast<std::size_t>(j)].allFinite());
      EXPECT_GT(s.confidence[static_cast<std::size_t>(j)], 0.0) << joint_name(static_cast<HandJoint>(j));
    }
    EXPECT_FALSE(s.pinch.active);
    EXPECT_FALSE(s.grip.active);
  }
}

TEST(HandSolver, BoneDirectionsGiveBackTheAnglesThatMadeThem) {
  // What a finger's segment stars measure (three bone directions) inverts forward kinematics,
  // for random poses within the limits of every chain of both hands.
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (const HandSide side : {HandSide::kLeft, HandSide::kRight}) {
    const auto chains = hand_chains(reference_open_hand(side), side);
    for (int trial = 0; trial < 200; ++trial) {
      for (const FingerChain& c : chains) {
        FingerAngles a;
        for (std::size_t k = 0; k < 3; ++k)
          a.flexion_rad[k] = c.limits.flexion_min_rad[k] + u(rng) * (c.limits.flexion_max_rad[k] - c.limits.flexion_min_rad[k]);
        a.abduction_rad = (2.0 * u(rng) - 1.0) * c.limits.abduction_max_rad;
        a = clamp_to_limits(c.limits, a);
        const auto p = finger_forward(c, a);
        const FingerAngles back = angles_from_bones(c, {p[1] - p[0], p[2] - p[1], p[3] - p[2]});
        EXPECT_NEAR(back.abduction_rad, a.abduction_rad, 1e-9);
        for (std::size_t k = 0; k < 3; ++k) EXPECT_NEAR(back.flexion_rad[k], a.flexion_rad[k], 1e-9) << k;
      }
    }
  }
}

TEST(HandSolver, MeasuredAnglesWinOverTheTipAndAreKeptWithinLimits) {
  const HandPose reference = reference_open_hand(HandSide::kRight);
  HandSolver solver(HandSide::kRight, reference);
  std::array<std::optional<FingerAngles>, kFingerCount> measured{};
  measured[1] = FingerAngles{0.1, {0.5, 2.5, 0.3}};  // PIP beyond its 110 degrees
  const HandState& s = solver.update(0.0, tips_of(reference), measured);
  EXPECT_DOUBLE_EQ(s.angles[1].abduction_rad, 0.1);
  EXPECT_DOUBLE_EQ(s.angles[1].flexion_rad[0], 0.5);
  EXPECT_DOUBLE_EQ(s.angles[1].flexion_rad[1], solver.chains()[1].limits.flexion_max_rad[1]);
  EXPECT_DOUBLE_EQ(s.angles[1].flexion_rad[2], 0.3);
  EXPECT_TRUE(s.tip_seen[1]);
}

TEST(HandSolver, WithNoFingerSeenAHiddenFingerHoldsThenEasesTowardRelaxed) {
  const HandPose reference = reference_open_hand(HandSide::kRight);
  HandSolver solver(HandSide::kRight, reference);
  // Curl the index finger: its tip under the knuckle; then no tip is seen at all.
  Tips tips = tips_of(reference);
  const std::size_t index_tip = static_cast<std::size_t>(HandJoint::kIndexTip);
  const Eigen::Vector3d knuckle = reference.position_m[static_cast<std::size_t>(HandJoint::kIndexProximal)];
  tips[1] = knuckle + Eigen::Vector3d(0.0, -0.045, 0.01);
  const double curled = solver.update(0.0, tips).angles[1].flexion_rad[1];
  EXPECT_GT(curled, 0.8);
  const double relaxed = HandSolver(HandSide::kRight, reference).state().angles[1].flexion_rad[1];
  double previous = curled;
  for (int f = 1; f <= 270; ++f) {
    const HandState& s = solver.update(f / 90.0, Tips{});
    EXPECT_LE(s.angles[1].flexion_rad[1], previous + 1e-12) << "never bends further: it was still";
    previous = s.angles[1].flexion_rad[1];
    EXPECT_FALSE(s.tip_seen[1]);
    if (f == 45) {
      EXPECT_NEAR(s.confidence[index_tip], 0.9 * std::exp(-0.5 / HandSolver::kRelaxTime_s), 1e-9);
    }
    if (f == 90) {
      EXPECT_NEAR(s.angles[1].flexion_rad[1], curled, 1e-9) << "held for kHold_s";
    }
  }
  // Then 2 s (four time constants) of easing: within 2 % of relaxed.
  const HandState& s = solver.state();
  EXPECT_NEAR(s.angles[1].flexion_rad[1], relaxed, 0.02 * std::abs(curled - relaxed) + 1e-9);
  EXPECT_LT(s.confidence[index_tip], 0.01);
}

TEST(HandSolver, AHiddenFingerBendsAsTheSeenFingersDoAndHoldsWhileTheyHold) {
  // A grasp closing: every finger from relaxed to curled over 1 s, the index tip hidden from 0.3 s
  // (its own bones hide its marker), then the hand holds for 1 s.
  const HandPose reference = reference_open_hand(HandSide::kRight);
  HandSolver solver(HandSide::kRight, reference);
  const auto& chains = solver.chains();
  const auto relaxed = solver.state().angles;
  auto curl_at = [&](std::size_t f, double t) {
    FingerAngles a = relaxed[f];
    const double w = std::clamp(t, 0.0, 1.0);
    for (std::size_t k = 0; k < 3; ++k) a.flexion_rad[k] += w * (0.5 * chains[f].limits.flexion_max_rad[k] - relaxed[f].flexion_rad[k]);
    return clamp_to_limits(chains[f].limits, a);
  };
  const std::size_t index_tip = static_cast<std::size_t>(HandJoint::kIndexTip);
  for (int f = 0; f <= 180; ++f) {
    const double t = f / 90.0;
    Tips tips;
    for (std::size_t k = 0; k < kFingerCount; ++k) tips[k] = finger_forward(chains[k], curl_at(k, t))[3];
    if (t >= 0.3) tips[1].reset();
    const HandState& s = solver.update(t, tips);
    if (t < 0.3) continue;
    EXPECT_FALSE(s.tip_seen[1]);
    EXPECT_DOUBLE_EQ(s.confidence[index_tip], HandSolver::kEstimatedConfidence) << "estimated, and says so";
  }
  // The truth: curled as the others. Relaxing would have left it at relaxed (bend ~0.2 rad at the PIP).
  const HandState& s = solver.state();
  const FingerAngles truth = curl_at(1, 2.0);
  double bend = 0.0, true_bend = 0.0, relaxed_bend = 0.0;
  for (std::size_t k = 0; k < 3; ++k) {
    bend += s.angles[1].flexion_rad[k];
    true_bend += truth.flexion_rad[k];
    relaxed_bend += relaxed[1].flexion_rad[k];
  }
  EXPECT_NEAR(bend, true_bend, 0.25 * std::abs(true_bend - relaxed_bend)) << "closed with the hand, within a quarter of the motion";
  const Eigen::Vector3d tip = s.pose.position_m[index_tip];
  EXPECT_LT((tip - finger_forward(chains[1], truth)[3]).norm(), 0.015) << "its tip within 15 mm of the truth";
}

TEST(Gestures, PinchAndGripHaveHysteresis) {
  const GestureSettings g;
  Gesture pinch;
  for (const auto& [gap, seen, active] : std::vector<std::tuple<double, bool, bool>>{{0.030, true, false},
                                                                                     {0.012, true, false},
                                                                                     {0.005, false, false},
                                                                                     {0.009, true, true},
                                                                                     {0.012, true, true},
                                                                                     {0.0149, true, true},
                                                                                     {0.016, true, false},
                                                                                     {0.012, true, false}}) {
    update_pinch(pinch, gap, seen, g);
    EXPECT_EQ(pinch.active, active) << "gap " << gap;
  }
  update_pinch(pinch, 0.005, true, g);
  EXPECT_EQ(pinch.activation, 1.0);
  update_pinch(pinch, std::nan(""), true, g);
  EXPECT_TRUE(pinch.active) << "a NaN gap changes nothing";
  update_pinch(pinch, 0.025, true, g);
  EXPECT_NEAR(pinch.activation, 0.5, 1e-12);
  Gesture grip;
  for (const auto& [curl, active] :
       std::vector<std::pair<double, bool>>{{0.3, false}, {0.6, false}, {0.7, true}, {0.5, true}, {0.4, false}}) {
    update_grip(grip, curl, g);
    EXPECT_EQ(grip.active, active) << "curl " << curl;
  }
}

// Thumb and index tips brought together where both can reach: a pinch; apart: released.
TEST(HandSolver, TipsTogetherPinch) {
  const HandPose reference = reference_open_hand(HandSide::kRight);
  HandSolver solver(HandSide::kRight, reference);
  const auto chains = solver.chains();
  // A point the index reaches that the thumb reaches too.
  std::optional<Eigen::Vector3d> meet;
  for (double f0 = 0.2; f0 < 1.5 && !meet; f0 += 0.1) {
    for (double f1 = 0.2; f1 < 1.8 && !meet; f1 += 0.1) {
      for (double ab = -0.25; ab <= 0.25 && !meet; ab += 0.05) {
        const Eigen::Vector3d p = finger_forward(chains[1], FingerAngles{ab, {f0, f1, 2.0 / 3.0 * f1}})[3];
        if (solve_fabrik(chains[0], p, {}, {50, 1e-5}).tip_error_m < 0.0005) meet = p;
      }
    }
  }
  ASSERT_TRUE(meet.has_value()) << "thumb and index cannot meet";
  Tips tips = tips_of(reference);
  tips[0] = *meet;
  tips[1] = *meet;
  for (int f = 0; f < 5; ++f) solver.update(f / 90.0, tips);
  EXPECT_TRUE(solver.state().pinch.active);
  tips = tips_of(reference);
  for (int f = 5; f < 10; ++f) solver.update(f / 90.0, tips);
  EXPECT_FALSE(solver.state().pinch.active);
}

TEST(HandSolver, RandomAndBrokenInputNeverGivesNaNOrBreaksALimit) {
  const HandPose reference = reference_open_hand(HandSide::kLeft);
  HandSolver solver(HandSide::kLeft, reference);
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-0.3, 0.3);
  std::uniform_int_distribution<int> kind(0, 5);
  for (int f = 0; f < 1000; ++f) {
    Tips tips;
    for (auto& t : tips) {
      switch (kind(rng)) {
        case 0:
          break;  // unseen
        case 1:
          t = Eigen::Vector3d(std::nan(""), 0, 0);
          break;
        case 2:
          t = Eigen::Vector3d(1e300, -1e300, 0);
          break;
        default:
          t = Eigen::Vector3d{u(rng), u(rng), u(rng)};
      }
    }
    const double time = kind(rng) == 0 ? std::nan("") : f / 90.0;
    const HandState& s = solver.update(time, tips);
    for (int j = 0; j < kHandJointCount; ++j) {
      ASSERT_TRUE(s.pose.position_m[static_cast<std::size_t>(j)].allFinite()) << f;
      ASSERT_TRUE(std::isfinite(s.confidence[static_cast<std::size_t>(j)]));
    }
    for (int k = 0; k < kFingerCount; ++k)
      ASSERT_TRUE(within_limits(solver.chains()[static_cast<std::size_t>(k)].limits, s.angles[static_cast<std::size_t>(k)])) << f;
    ASSERT_TRUE(std::isfinite(s.pinch.activation) && std::isfinite(s.grip.activation));
  }
}

TEST(HandSolver, AFistIsAGrip) {
  const HandPose reference = reference_open_hand(HandSide::kRight);
  HandSolver solver(HandSide::kRight, reference);
  Tips tips = tips_of(reference);
  for (int f = 2; f < kFingerCount; ++f) {
    const FingerChain& c = solver.chains()[static_cast<std::size_t>(f)];
    FingerAngles fist;
    fist.flexion_rad = {1.4, 1.6, c.limits.coupling * 1.6};
    tips[static_cast<std::size_t>(f)] = finger_forward(c, fist)[3];
  }
  EXPECT_TRUE(solver.update(0.0, tips).grip.active);
  EXPECT_FALSE(solver.update(0.1, tips_of(reference)).grip.active);
}

}  // namespace
}  // namespace rhot
