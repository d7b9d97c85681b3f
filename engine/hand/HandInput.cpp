#include "engine/hand/HandInput.h"

namespace rhot {

namespace {

constexpr std::array<HandBone, kHandBoneCount> kBones{{
    {HandJoint::kThumbMetacarpal, HandJoint::kThumbProximal, 0},
    {HandJoint::kThumbProximal, HandJoint::kThumbDistal, 0},
    {HandJoint::kThumbDistal, HandJoint::kThumbTip, 0},
    {HandJoint::kIndexMetacarpal, HandJoint::kIndexProximal, kPalmGroup},
    {HandJoint::kIndexProximal, HandJoint::kIndexIntermediate, 1},
    {HandJoint::kIndexIntermediate, HandJoint::kIndexDistal, 1},
    {HandJoint::kIndexDistal, HandJoint::kIndexTip, 1},
    {HandJoint::kMiddleMetacarpal, HandJoint::kMiddleProximal, kPalmGroup},
    {HandJoint::kMiddleProximal, HandJoint::kMiddleIntermediate, 2},
    {HandJoint::kMiddleIntermediate, HandJoint::kMiddleDistal, 2},
    {HandJoint::kMiddleDistal, HandJoint::kMiddleTip, 2},
    {HandJoint::kRingMetacarpal, HandJoint::kRingProximal, kPalmGroup},
    {HandJoint::kRingProximal, HandJoint::kRingIntermediate, 3},
    {HandJoint::kRingIntermediate, HandJoint::kRingDistal, 3},
    {HandJoint::kRingDistal, HandJoint::kRingTip, 3},
    {HandJoint::kLittleMetacarpal, HandJoint::kLittleProximal, kPalmGroup},
    {HandJoint::kLittleProximal, HandJoint::kLittleIntermediate, 4},
    {HandJoint::kLittleIntermediate, HandJoint::kLittleDistal, 4},
    {HandJoint::kLittleDistal, HandJoint::kLittleTip, 4},
}};

}  // namespace

const std::array<HandBone, kHandBoneCount>& hand_bones() { return kBones; }

HandInput hand_input(const Rigid3d& world_from_hand, const HandPose& pose) {
  HandInput in;
  in.seen = true;
  in.world_from_hand = world_from_hand;
  for (std::size_t j = 0; j < kHandJointCount; ++j) in.joints_world[j] = world_from_hand * pose.position_m[j];
  in.radius_m = pose.radius_m;
  in.confidence.fill(1.0);
  return in;
}

}  // namespace rhot
