#pragma once
// Scripted hands for physics tests and rhot-eval grasp: a grasp of an object of a given width
// between the thumb and one or two fingers, built from the reference hand's finger chains with
// FABRIK, and a hand pose for any closure between open (0) and squeezing (1).

#include <array>

#include "tracking/core/Rigid3.h"
#include "tracking/hand/HandSolver.h"

namespace rhot {

struct GraspPose {
  HandSide side = HandSide::kRight;
  HandPose skeleton;
  std::array<FingerChain, kFingerCount> chains;
  std::array<FingerAngles, kFingerCount> open{};         // thumb out, fingers nearly straight
  std::array<FingerAngles, kFingerCount> closed{};       // grasping tips `squeeze_m` inside the object
  Eigen::Vector3d grip_point = Eigen::Vector3d::Zero();  // object centre, hand frame
  Eigen::Vector3d grip_axis = Eigen::Vector3d::UnitX();  // unit, thumb toward the fingers, hand frame
  double reach_error_m = 0.0;                            // how far the closed tips' gap is from the one wanted (a too wide object)

  // The hand at a closure (0 open .. 1 closed), hand frame.
  HandPose pose(double closure) const;
  // The hand frame that puts the grip point at `centre` with the grip axis along `axis` (world,
  // unit, horizontal) and the palm facing down.
  Rigid3d place(const Eigen::Vector3d& centre, const Eigen::Vector3d& axis) const;
};

// `fingers`: 1 (index) or 2 (index and middle) against the thumb. The other fingers stay relaxed.
GraspPose make_grasp(HandSide side, double width_m, double squeeze_m = 0.006, int fingers = 2);

// A hand pointing its index finger straight (the others curled into the palm), for pushing.
HandPose pointing_hand(HandSide side);

}  // namespace rhot
