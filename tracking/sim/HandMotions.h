#pragma once
// Scripted hand motions for the simulated rig: ground-truth skeletons over time (the hand frame's
// pose and every finger's angles), from which the simulation places markers and occluders.
//
// Every motion moves the hand (palm down, fingers forward) through a few centimetres around a
// centre, and blends the fingers from the relaxed pose to the motion's pose and back every 2 s:
//   open (fingers spread straight), fist, pinch (thumb and index tips meet), wave (the hand turning
//   about the forearm, fingers straight), power-grasp (all fingers around a 4 cm cylinder),
//   precision-grasp (thumb, index and middle around a 3 cm sphere).

#include <array>
#include <optional>
#include <span>
#include <string_view>

#include "tracking/core/Rigid3.h"
#include "tracking/hand/HandSolver.h"

namespace rhot {

struct HandMotionFrame {
  Rigid3d world_from_hand;
  std::array<FingerAngles, kFingerCount> angles{};
};

std::span<const std::string_view> hand_motion_names();

// Nothing for an unknown name. `relaxed` are the angles the motion starts from and returns to.
std::optional<HandMotionFrame> hand_motion(std::string_view name, double t_s, const std::array<FingerChain, kFingerCount>& chains,
                                           const std::array<FingerAngles, kFingerCount>& relaxed, const Eigen::Vector3d& centre_m);

// The 26 joints of a hand in its frame: palm, wrist and metacarpals from `skeleton`, the fingers from
// their chains at `angles`.
HandPose hand_pose_from_angles(const HandPose& skeleton, const std::array<FingerChain, kFingerCount>& chains,
                               const std::array<FingerAngles, kFingerCount>& angles);

}  // namespace rhot
