#include "tracking/hand/JointFrames.h"

#include <cmath>

namespace rhot {

std::optional<HandJoint> joint_child(HandJoint joint) {
  const int j = static_cast<int>(joint);
  if (j <= static_cast<int>(HandJoint::kWrist)) return std::nullopt;
  const bool tip = j == static_cast<int>(HandJoint::kThumbTip) || (j >= 10 && (j - 10) % 5 == 0);
  if (tip) return std::nullopt;
  return static_cast<HandJoint>(j + 1);
}

namespace {

// A frame whose -Z is `along` (unit), with X as near `lateral` as can be.
Eigen::Quaterniond frame_along(const Eigen::Vector3d& along, const Eigen::Vector3d& lateral) {
  const Eigen::Vector3d z = -along;
  const Eigen::Vector3d x = (lateral - lateral.dot(z) * z).normalized();
  Eigen::Matrix3d m;
  m.col(0) = x;
  m.col(1) = z.cross(x);
  m.col(2) = z;
  return Eigen::Quaterniond(m).normalized();
}

bool is_thumb(HandJoint joint) { return joint >= HandJoint::kThumbMetacarpal && joint <= HandJoint::kThumbTip; }

}  // namespace

std::array<Eigen::Quaterniond, kHandJointCount> joint_orientations(const Eigen::Quaterniond& world_from_hand,
                                                                   const std::array<Eigen::Vector3d, kHandJointCount>& joints_world) {
  std::array<Eigen::Quaterniond, kHandJointCount> out;
  const Eigen::Quaterniond hand = world_from_hand.normalized();
  const Eigen::Vector3d hand_x = hand * Eigen::Vector3d::UnitX();
  const Eigen::Vector3d hand_y = hand * Eigen::Vector3d::UnitY();
  out[static_cast<std::size_t>(HandJoint::kPalm)] = hand;
  out[static_cast<std::size_t>(HandJoint::kWrist)] = hand;
  for (int j = static_cast<int>(HandJoint::kThumbMetacarpal); j < kHandJointCount; ++j) {
    const auto joint = static_cast<HandJoint>(j);
    const auto child = joint_child(joint);
    if (!child) {
      out[static_cast<std::size_t>(j)] = out[static_cast<std::size_t>(j - 1)];  // a tip: its distal joint's
      continue;
    }
    const Eigen::Vector3d bone = joints_world[static_cast<std::size_t>(*child)] - joints_world[static_cast<std::size_t>(j)];
    const double length = bone.norm();
    if (!(length > 1e-9) || !std::isfinite(length)) {
      out[static_cast<std::size_t>(j)] = hand;  // a bone of no length has no direction
      continue;
    }
    const Eigen::Vector3d along = bone / length;
    // Fingers bend about the hand's X; the thumb's bones can point along it, so its lateral axis
    // is the back of the hand crossed with the bone (Y x Z), unless the thumb points (nearly)
    // straight out of the back or the palm.
    Eigen::Vector3d lateral = hand_x;
    if (is_thumb(joint)) {
      const Eigen::Vector3d across = hand_y.cross(-along);
      if (across.norm() > 0.1) lateral = across;
    }
    out[static_cast<std::size_t>(j)] = frame_along(along, lateral);
  }
  return out;
}

}  // namespace rhot
