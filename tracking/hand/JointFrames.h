#pragma once
// The orientation of every hand joint from the joints' positions and the hand frame, as OpenXR
// gives them (XR_EXT_hand_tracking): a joint's -Z runs along its bone toward the next joint (the
// fingertip end), +Y out of the back of the hand, +X = Y x Z. What exporters and streams need where
// a skeleton's bones carry rotations (BVH, the VMC protocol).
//
// - palm and wrist: the hand frame itself;
// - every other joint with a next joint: -Z along its bone; X the hand frame's X made
//   perpendicular to the bone (for the thumb, whose bones can point along the hand's X: the
//   hand's +Y crossed with the bone's +Z, unless the thumb points nearly along +-Y);
// - tips: their distal joint's orientation.
//
// So a bone's next joint sits at a fixed offset in its joint's frame, (0, 0, -length): a skeleton
// of fixed bone lengths is reproduced exactly by these rotations.

#include <array>
#include <optional>

#include <Eigen/Geometry>

#include "tracking/hand/HandJoints.h"

namespace rhot {

// The next joint along the bone a joint's frame follows (its child toward the tip); none for tips.
std::optional<HandJoint> joint_child(HandJoint joint);

// World orientations of the 26 joints (unit quaternions).
std::array<Eigen::Quaterniond, kHandJointCount> joint_orientations(const Eigen::Quaterniond& world_from_hand,
                                                                   const std::array<Eigen::Vector3d, kHandJointCount>& joints_world);

}  // namespace rhot
