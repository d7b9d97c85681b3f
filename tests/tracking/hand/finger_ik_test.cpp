#include "tracking/hand/FingerIK.h"

#include <numbers>
#include <random>

#include <gtest/gtest.h>

#include "tracking/hand/HandJoints.h"

namespace rhot {
namespace {

// An index finger of adult size, right hand palm down: knuckle 9 cm ahead of the wrist.
FingerChain index_finger() {
  FingerChain c;
  c.root_m = {-0.026, 0.0, -0.090};
  c.rest_direction = Eigen::Vector3d(-0.1, 0.0, -1.0).normalized();
  c.up = Eigen::Vector3d::UnitY();
  c.length_m = {0.040, 0.024, 0.020};
  return c;
}

FingerAngles random_angles(std::mt19937_64& rng, const FingerLimits& l) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  FingerAngles a;
  a.flexion_rad[0] = l.flexion_max_rad[0] * u(rng);
  a.flexion_rad[1] = l.flexion_max_rad[1] * u(rng);
  a.flexion_rad[2] = l.coupling * a.flexion_rad[1];
  a.abduction_rad = (2.0 * u(rng) - 1.0) * l.abduction_max_rad;
  return clamp_to_limits(l, a);
}

TEST(HandJoints, OpenXrNamesAndOrder) {
  EXPECT_EQ(kHandJointCount, 26);
  EXPECT_EQ(joint_name(HandJoint::kPalm), "palm");
  EXPECT_EQ(joint_name(HandJoint::kWrist), "wrist");
  EXPECT_EQ(joint_name(HandJoint::kThumbMetacarpal), "thumb_metacarpal");
  EXPECT_EQ(joint_name(HandJoint::kIndexIntermediate), "index_intermediate");
  EXPECT_EQ(joint_name(HandJoint::kLittleTip), "little_tip");
  EXPECT_EQ(static_cast<int>(HandJoint::kThumbTip), 5);
  EXPECT_EQ(static_cast<int>(HandJoint::kIndexMetacarpal), 6);
  EXPECT_EQ(static_cast<int>(HandJoint::kLittleTip), 25);
  EXPECT_EQ(joint_parent(HandJoint::kIndexTip), HandJoint::kIndexDistal);
  EXPECT_EQ(joint_parent(HandJoint::kIndexMetacarpal), HandJoint::kWrist);
  EXPECT_FALSE(joint_parent(HandJoint::kWrist).has_value());
}

TEST(FingerIK, ForwardKinematicsOfAStraightAndABentFinger) {
  const FingerChain c = index_finger();
  const auto straight = finger_forward(c, {});
  EXPECT_LT((straight[3] - (c.root_m + 0.084 * c.rest_direction)).norm(), 1e-12);
  FingerAngles bent;
  bent.flexion_rad = {std::numbers::pi / 2, 0.0, 0.0};  // the whole finger points at the palm
  const auto down = finger_forward(c, bent);
  EXPECT_LT((down[3] - (c.root_m - 0.084 * c.up)).norm(), 1e-12);
}

TEST(FingerIK, FabrikReachesEveryReachablePoseWithinLimits) {
  const FingerChain c = index_finger();
  std::mt19937_64 rng(1);
  double worst_error = 0.0;
  double sum_error = 0.0;
  for (int trial = 0; trial < 2000; ++trial) {
    const FingerAngles truth = random_angles(rng, c.limits);
    const Eigen::Vector3d target = finger_forward(c, truth)[3];
    const IkResult r = solve_fabrik(c, target);
    EXPECT_TRUE(within_limits(c.limits, r.angles)) << "trial " << trial;
    worst_error = std::max(worst_error, r.tip_error_m);
    sum_error += r.tip_error_m;
  }
  // Constrained FABRIK converges linearly near the limits and the coupling: in its 20 iterations
  // it gets to 0.12 mm on average, 0.65 mm at worst (docs/PERFORMANCE.md).
  EXPECT_LT(sum_error / 2000, 0.00015);
  EXPECT_LT(worst_error, 0.001);
}

TEST(FingerIK, DlsReachesTheSamePoses) {
  const FingerChain c = index_finger();
  std::mt19937_64 rng(2);
  IkSettings s;
  s.max_iterations = 50;
  double worst_error = 0.0;
  for (int trial = 0; trial < 500; ++trial) {
    const FingerAngles truth = random_angles(rng, c.limits);
    const IkResult r = solve_dls(c, finger_forward(c, truth)[3], {}, s);
    EXPECT_TRUE(within_limits(c.limits, r.angles));
    worst_error = std::max(worst_error, r.tip_error_m);
  }
  EXPECT_LT(worst_error, 0.002);
}

TEST(FingerIK, TheLastHingeFollowsTheMiddleOne) {
  const FingerChain c = index_finger();
  std::mt19937_64 rng(3);
  for (int trial = 0; trial < 200; ++trial) {
    const IkResult r = solve_fabrik(c, finger_forward(c, random_angles(rng, c.limits))[3]);
    EXPECT_NEAR(r.angles.flexion_rad[2], std::min(c.limits.coupling * r.angles.flexion_rad[1], c.limits.flexion_max_rad[2]), 1e-12);
  }
}

TEST(FingerIK, LimitsHoldForUnreachableAndAbsurdTargets) {
  const FingerChain c = index_finger();
  std::mt19937_64 rng(4);
  std::uniform_real_distribution<double> u(-0.3, 0.3);
  for (int trial = 0; trial < 500; ++trial) {
    // Anywhere around the hand, including behind the knuckle and bent backwards.
    const Eigen::Vector3d target = c.root_m + Eigen::Vector3d{u(rng), u(rng), u(rng)};
    for (const IkResult& r : {solve_fabrik(c, target), solve_dls(c, target)}) {
      EXPECT_TRUE(within_limits(c.limits, r.angles)) << "trial " << trial;
      EXPECT_TRUE(std::isfinite(r.tip_error_m));
      for (const Eigen::Vector3d& p : finger_forward(c, r.angles)) EXPECT_TRUE(p.allFinite());
    }
  }
  // The middle finger does not abduct.
  FingerChain middle = c;
  middle.limits.abduction_max_rad = 0.0;
  EXPECT_EQ(solve_fabrik(middle, c.root_m + Eigen::Vector3d(0.05, -0.02, -0.05)).angles.abduction_rad, 0.0);
}

TEST(FingerIK, NonFiniteInputNeverBecomesNaN) {
  const FingerChain c = index_finger();
  const double nan = std::nan(""), inf = std::numeric_limits<double>::infinity();
  FingerAngles start;
  start.flexion_rad = {nan, inf, -inf};
  start.abduction_rad = nan;
  for (const Eigen::Vector3d& target : {Eigen::Vector3d(nan, 0, 0), Eigen::Vector3d(inf, 1, 1), Eigen::Vector3d(0, 0, -0.1)}) {
    for (const IkResult& r : {solve_fabrik(c, target, start), solve_dls(c, target, start)}) {
      EXPECT_TRUE(std::isfinite(r.angles.abduction_rad));
      for (const double f : r.angles.flexion_rad) EXPECT_TRUE(std::isfinite(f));
      EXPECT_TRUE(within_limits(c.limits, r.angles));
    }
  }
}

TEST(FingerIK, TheEllipseShrinksAbductionAsTheFingerFlexes) {
  const FingerLimits l;
  FingerAngles a;
  a.abduction_rad = 0.26;
  EXPECT_TRUE(within_limits(l, a));
  a.flexion_rad[0] = 0.9 * l.flexion_max_rad[0];
  EXPECT_FALSE(within_limits(l, a)) << "15 degrees of abduction with the knuckle bent 81 degrees";
  EXPECT_NEAR(clamp_to_limits(l, a).abduction_rad, l.abduction_max_rad * std::sqrt(1.0 - 0.81), 1e-12);
}

}  // namespace
}  // namespace rhot
