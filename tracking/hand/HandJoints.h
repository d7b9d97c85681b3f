#pragma once
// The 26 hand joints of OpenXR's XR_EXT_hand_tracking, in its order, with its names (the
// XR_HAND_JOINT_..._EXT names lower-cased and shortened: "index_proximal"), the bones between
// them, and a reference open-hand pose to draw and test with until the tracker supplies real
// skeletons.
//
// Hand frame: origin at the wrist joint, fingers along -Z, the back of the hand along +Y; the
// right hand's thumb is toward -X (palm down), the left hand's toward +X. Metres.

#include <array>
#include <cstdint>
#include <optional>
#include <string_view>

#include <Eigen/Core>

namespace rhot {

enum class HandJoint : std::uint8_t {
  kPalm = 0,
  kWrist,
  kThumbMetacarpal,
  kThumbProximal,
  kThumbDistal,
  kThumbTip,
  kIndexMetacarpal,
  kIndexProximal,
  kIndexIntermediate,
  kIndexDistal,
  kIndexTip,
  kMiddleMetacarpal,
  kMiddleProximal,
  kMiddleIntermediate,
  kMiddleDistal,
  kMiddleTip,
  kRingMetacarpal,
  kRingProximal,
  kRingIntermediate,
  kRingDistal,
  kRingTip,
  kLittleMetacarpal,
  kLittleProximal,
  kLittleIntermediate,
  kLittleDistal,
  kLittleTip,
};
inline constexpr int kHandJointCount = 26;

enum class HandSide : std::uint8_t { kLeft, kRight };

std::string_view joint_name(HandJoint joint);

// The joint this one hangs from (its bone runs parent -> joint); none for the wrist and palm.
std::optional<HandJoint> joint_parent(HandJoint joint);

struct HandPose {
  std::array<Eigen::Vector3d, kHandJointCount> position_m;  // hand frame
  std::array<double, kHandJointCount> radius_m;             // joint radius: distance to the skin
};

// A relaxed open hand with adult bone lengths, fingers slightly curled.
HandPose reference_open_hand(HandSide side);

}  // namespace rhot
