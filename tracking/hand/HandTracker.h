#pragma once
// A hand from triangulated points, with a layout (HandLayout.h): the hand star gives the hand
// frame (StarTracker), the points left near each fingertip's predicted marker are its marker
// (nearest first, each point once), and HandSolver fits the fingers.

#include <optional>
#include <span>
#include <vector>

#include "tracking/filter/OneEuroFilter.h"
#include "tracking/hand/HandLayout.h"
#include "tracking/hand/HandSolver.h"
#include "tracking/rigid/StarTracker.h"

namespace rhot {

struct TrackedHand {
  bool hand_seen = false;   // the hand star was seen this frame
  Rigid3d world_from_hand;  // last known
  HandState state;          // hand frame
  std::array<Eigen::Vector3d, kHandJointCount> joints_world{};
  std::array<int, kFingerCount> fingertip_point{-1, -1, -1, -1, -1};  // index into the points, -1 for none
  int segment_stars_seen = 0;
};

struct HandTrackerSettings {
  // 1-euro filtering of the hand frame and of each fingertip target (hand frame) before the IK.
  bool filter = false;
  OneEuroSettings position;  // for the hand's origin and the fingertips, metres
  OneEuroSettings rotation{1.0, 2.0, 1.0};
};

class HandTracker {
 public:
  HandTracker(const HandLayout& layout, const HandPose& skeleton, HandTrackerSettings settings = {});

  // points_world with each one's standard deviation per axis (metres; empty: the star library's default).
  const TrackedHand& update(double time_s, std::span<const Eigen::Vector3d> points_world, std::span<const double> sigma_m = {});
  const HandSolver& solver() const { return solver_; }
  const TrackedHand& last() const { return out_; }  // the last update's result
  // Time spent in HandSolver::update (the IK) on the last frame.
  double last_ik_us() const { return last_ik_us_; }

  static constexpr double kFingertipGate_m = 0.04;

 private:
  HandLayout layout_;
  HandTrackerSettings settings_;
  StarTracker star_;
  std::optional<StarTracker> segments_;  // the layout's segment stars, if any
  PoseFilter hand_filter_;
  std::array<OneEuroFilter<3>, kFingerCount> tip_filters_;
  HandSolver solver_;
  TrackedHand out_;
  double last_ik_us_ = 0.0;
};

}  // namespace rhot
