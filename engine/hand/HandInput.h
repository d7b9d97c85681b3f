#pragma once
// A tracked hand as the engine takes it, whatever tracked it (live cameras, a recording, a
// script): the hand frame and the 26 OpenXR joints in the world, with radii and per-joint
// confidence. Physics drives its colliders from this; recordings store it.

#include <array>

#include "tracking/core/Rigid3.h"
#include "tracking/hand/HandJoints.h"

namespace rhot {

// One hand's tracking result, in the world frame.
struct HandInput {
  bool seen = false;
  Rigid3d world_from_hand;  // the hand frame (tracking/hand/HandJoints.h)
  std::array<Eigen::Vector3d, kHandJointCount> joints_world{};
  std::array<double, kHandJointCount> radius_m{};
  std::array<double, kHandJointCount> confidence{};  // 1: measured this frame; less: inferred
};

// A hand in a pose, every joint fully confident (scripted hands).
HandInput hand_input(const Rigid3d& world_from_hand, const HandPose& pose);

inline constexpr int kHandBoneCount = 19;
inline constexpr int kPalmGroup = 5;  // bone groups: 0 thumb .. 4 little, 5 the palm (metacarpals)

struct HandBone {
  HandJoint from;
  HandJoint to;
  int group;  // finger 0-4 or kPalmGroup
};
const std::array<HandBone, kHandBoneCount>& hand_bones();

}  // namespace rhot
