#include "tracking/hand/FingerFit.h"

#include <cmath>
#include <random>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "tracking/hand/HandSolver.h"

namespace rhot {
namespace {

// A glove's two markers on a finger (assets/hands/glove-13-right.json): on the nail, 10 mm above
// the last bone and 6 mm short of the tip, and on the proximal bone.
FingerPoint nail(const FingerChain& c, const FingerAngles& a) {
  FingerPoint p{3, Eigen::Vector3d(0.0, 0.010, 0.006), Eigen::Vector3d::Zero(), 1.0};
  p.at_m = finger_point_at(c, a, p);
  return p;
}
FingerPoint proximal(const FingerChain& c, const FingerAngles& a) {
  FingerPoint p{0, Eigen::Vector3d(0.0, 0.014, -0.021), Eigen::Vector3d::Zero(), 0.25};
  p.at_m = finger_point_at(c, a, p);
  return p;
}

// Anywhere within the limits, the last hinge free of the middle one.
FingerAngles any_angles_within(std::mt19937_64& rng, const FingerLimits& l) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  FingerAngles a;
  for (std::size_t k = 0; k < 3; ++k) a.flexion_rad[k] = l.flexion_min_rad[k] + u(rng) * (l.flexion_max_rad[k] - l.flexion_min_rad[k]);
  a.abduction_rad = (2.0 * u(rng) - 1.0) * l.abduction_max_rad;
  return clamp_to_limits(l, a);
}

FingerAngles nudged(std::mt19937_64& rng, const FingerLimits& l, FingerAngles a, double by_rad) {
  std::uniform_real_distribution<double> u(-by_rad, by_rad);
  a.abduction_rad += u(rng);
  for (double& v : a.flexion_rad) v += u(rng);
  return clamp_to_limits(l, a);
}

double angle_gap(const FingerAngles& a, const FingerAngles& b) {
  double gap = std::abs(a.abduction_rad - b.abduction_rad);
  for (std::size_t k = 0; k < 3; ++k) gap = std::max(gap, std::abs(a.flexion_rad[k] - b.flexion_rad[k]));
  return gap;
}

TEST(FingerFit, ATipAndAMiddleMarkerGiveBackEveryJointOfEveryFingerWithTheLastHingeFree) {
  const auto chains = hand_chains(reference_open_hand(HandSide::kRight), HandSide::kRight);
  FingerFitSettings exact;
  exact.coupling_m = 0.0;  // no prior: six equations, four angles, an exact fit
  std::mt19937_64 rng(1);
  double worst_default_m = 0.0, default_sum_m = 0.0;
  int recovered = 0;
  for (std::size_t f = 0; f < chains.size(); ++f) {
    const FingerChain& c = chains[f];
    for (int i = 0; i < 200; ++i) {
      const FingerAngles truth = any_angles_within(rng, c.limits);
      // Near the edges the limits decide; a pose a frame away from the last one is what a tracker meets.
      const FingerAngles start = nudged(rng, c.limits, truth, 0.08);
      const std::array<FingerPoint, 2> points{nail(c, truth), proximal(c, truth)};
      const FingerFit fit = fit_finger(c, points, start, exact);
      EXPECT_LT(fit.rms_m, 1e-6) << "finger " << f << " pose " << i;
      EXPECT_TRUE(within_limits(c.limits, fit.angles));
      // Two markers pin all four angles, but for the planar two-link choice of the last two hinges:
      // where both bendings are within the limits, the other one fits as exactly.
      if (f != 0) recovered += angle_gap(fit.angles, truth) < 1e-3 ? 1 : 0;
      // With the default prior, the last hinge held a little toward the coupling: a small miss,
      // larger the further a pose is from the coupling (a fully bent middle joint with the last
      // one straight, which a free draw makes and a hand rarely does).
      const double off_coupling = std::abs(truth.flexion_rad[2] - c.limits.coupling * truth.flexion_rad[1]);
      const double miss = fit_finger(c, points, start).rms_m;
      default_sum_m += miss;
      if (off_coupling < 0.5) worst_default_m = std::max(worst_default_m, miss);
    }
  }
  EXPECT_GE(recovered, 770);  // of 800 finger poses
  // Measured: 0.15 mm on average, 0.54 mm at worst within 0.5 rad of the coupling (a thumb; 0.26 mm a finger).
  EXPECT_LT(default_sum_m / 1000.0, 0.3e-3);
  EXPECT_LT(worst_default_m, 1.0e-3);
}

TEST(FingerFit, APointIsWhereTheLayoutPutsItsMarkerOnTheHandsOwnFingers) {
  // What the tracker reports (HandTracker::markers_in_hand: layout_marker_in_hand with the
  // solver's own chains) is where the fit put each point, for a calibrated hand's turned fingers too.
  HandPose hand = reference_open_hand(HandSide::kRight);
  auto chains = hand_chains(hand, HandSide::kRight);
  const Eigen::Vector3d lateral = chains[2].rest_direction.cross(chains[2].up).normalized();
  const Eigen::Matrix3d turn = (Eigen::AngleAxisd(0.3, chains[2].up) * Eigen::AngleAxisd(0.25, lateral)).toRotationMatrix();
  chains[2].rest_direction = turn * chains[2].rest_direction;
  chains[2].up = turn * chains[2].up;
  std::mt19937_64 rng(4);
  for (int i = 0; i < 50; ++i) {
    std::array<FingerAngles, kFingerCount> angles;
    for (std::size_t f = 0; f < kFingerCount; ++f) {
      angles[f] = any_angles_within(rng, chains[f].limits);
      const auto joints = finger_forward(chains[f], angles[f]);
      const auto named = chain_joints(static_cast<Finger>(f));
      for (std::size_t k = 0; k < 4; ++k) hand.position_m[static_cast<std::size_t>(named[k])] = joints[k];
    }
    const auto frames = marker_frames(hand, chains);
    for (std::size_t f = 0; f < kFingerCount; ++f) {
      const auto named = chain_joints(static_cast<Finger>(f));
      for (std::size_t k = 0; k < 4; ++k) {
        const LayoutMarker marker{"m", named[k], Eigen::Vector3d(0.003, 0.011, -0.007), -1};
        const Eigen::Vector3d fitted = finger_point_at(chains[f], angles[f], finger_point(marker, Eigen::Vector3d::Zero(), 1.0));
        EXPECT_LT((fitted - layout_marker_in_hand(marker, hand, frames)).norm(), 1e-9) << "finger " << f << " joint " << k;
      }
    }
  }
}

TEST(FingerFit, ALoneNailMarkerIsReachedWithTheLastHingeFollowingTheMiddleOne) {
  const auto chains = hand_chains(reference_open_hand(HandSide::kRight), HandSide::kRight);
  const FingerChain& c = chains[1];
  std::mt19937_64 rng(2);
  int fitted = 0;
  for (int i = 0; i < 300; ++i) {
    FingerAngles truth = any_angles_within(rng, c.limits);
    truth.flexion_rad[2] = c.limits.coupling * truth.flexion_rad[1];
    truth = clamp_to_limits(c.limits, truth);
    const std::array<FingerPoint, 1> points{nail(c, truth)};
    const FingerFit fit = fit_finger(c, points, nudged(rng, c.limits, truth, 0.08));
    EXPECT_LT(fit.rms_m, 2e-5) << "pose " << i;
    // Three equations, four angles: the coupling settles the fourth.
    EXPECT_LT(std::abs(fit.angles.flexion_rad[2] - c.limits.coupling * fit.angles.flexion_rad[1]), 0.02) << "pose " << i;
    fitted += angle_gap(fit.angles, truth) < 0.02 ? 1 : 0;
  }
  EXPECT_GE(fitted, 295);
}

TEST(FingerFit, AFingerTurnedByACalibrationIsFittedAsExactly) {
  // A calibration turns a finger's rest direction about its knuckle and lengthens it
  // (HandCalibration.h); its markers turn with its plane.
  const auto reference = hand_chains(reference_open_hand(HandSide::kRight), HandSide::kRight);
  FingerChain c = reference[3];
  const Eigen::Vector3d lateral = c.rest_direction.cross(c.up).normalized();
  const Eigen::Matrix3d turn = (Eigen::AngleAxisd(0.25, c.up) * Eigen::AngleAxisd(-0.2, lateral)).toRotationMatrix();
  c.rest_direction = turn * c.rest_direction;
  c.up = turn * c.up;
  for (double& l : c.length_m) l *= 1.2;
  std::mt19937_64 rng(3);
  for (int i = 0; i < 200; ++i) {
    const FingerAngles truth = any_angles_within(rng, c.limits);
    const std::array<FingerPoint, 2> points{nail(c, truth), proximal(c, truth)};
    FingerFitSettings exact;
    exact.coupling_m = 0.0;
    const FingerFit fit = fit_finger(c, points, nudged(rng, c.limits, truth, 0.08), exact);
    EXPECT_LT(fit.rms_m, 1e-6) << "pose " << i;
  }
}

TEST(FingerFit, OutOfReachItStaysWithinTheLimitsAndNothingFiniteIsNothing) {
  const auto chains = hand_chains(reference_open_hand(HandSide::kRight), HandSide::kRight);
  const FingerChain& c = chains[2];
  // Far beyond the straight finger: it points there, straight, and misses by the difference.
  FingerPoint far{3, Eigen::Vector3d::Zero(), c.root_m + 0.3 * c.rest_direction, 1.0};
  const FingerFit reach = fit_finger(c, std::array{far}, FingerAngles{});
  EXPECT_TRUE(within_limits(c.limits, reach.angles));
  const double length = c.length_m[0] + c.length_m[1] + c.length_m[2];
  EXPECT_NEAR(reach.rms_m, 0.3 - length, 1e-4);
  // Behind the hand's back, bent past what a knuckle can: the nearest pose within the limits.
  FingerPoint behind{3, Eigen::Vector3d::Zero(), c.root_m + 0.06 * c.up, 1.0};
  const FingerFit bent = fit_finger(c, std::array{behind}, FingerAngles{});
  EXPECT_TRUE(within_limits(c.limits, bent.angles));
  EXPECT_GT(bent.rms_m, 0.02);
  // Points that are not finite are no points: the start comes back, clamped into the limits.
  FingerPoint nan{3, Eigen::Vector3d::Zero(), Eigen::Vector3d::Constant(std::nan("")), 1.0};
  FingerPoint infinite_weight{3, Eigen::Vector3d::Zero(), c.root_m, std::numeric_limits<double>::infinity()};
  FingerAngles start;
  start.flexion_rad = {3.0, -1.0, 0.5};
  FingerPoint nan_offset{3, Eigen::Vector3d(0.0, std::nan(""), 0.0), c.root_m, 1.0};
  const FingerFit none = fit_finger(c, std::array{nan, infinite_weight, nan_offset}, start);
  EXPECT_EQ(none.iterations, 0);
  EXPECT_TRUE(within_limits(c.limits, none.angles));
  EXPECT_DOUBLE_EQ(none.angles.flexion_rad[2], 0.5);
  // A start that is not finite starts from zero: the fit still reaches a point within reach.
  FingerAngles broken;
  broken.abduction_rad = std::nan("");
  broken.flexion_rad = {std::numeric_limits<double>::infinity(), std::nan(""), 0.2};
  FingerAngles curled;
  curled.flexion_rad = {0.6, 0.7, 0.45};
  const FingerFit from_nan = fit_finger(c, std::array{nail(c, curled)}, broken);
  EXPECT_TRUE(within_limits(c.limits, from_nan.angles));
  EXPECT_LT(from_nan.rms_m, 1e-4);
}

}  // namespace
}  // namespace rhot
