#include "tracking/hand/HandJoints.h"

namespace rhot {

std::string_view joint_name(HandJoint joint) {
  static constexpr std::array<std::string_view, kHandJointCount> kNames{"palm",
                                                                        "wrist",
                                                                        "thumb_metacarpal",
                                                                        "thumb_proximal",
                                                                        "thumb_distal",
                                                                        "thumb_tip",
                                                                        "index_metacarpal",
                                                                        "index_proximal",
                                                                        "index_intermediate",
                                                                        "index_distal",
                                                                        "index_tip",
                                                                        "middle_metacarpal",
                                                                        "middle_proximal",
                                                                        "middle_intermediate",
                                                                        "middle_distal",
                                                                        "middle_tip",
                                                                        "ring_metacarpal",
                                                                        "ring_proximal",
                                                                        "ring_intermediate",
                                                                        "ring_distal",
                                                                        "ring_tip",
                                                                        "little_metacarpal",
                                                                        "little_proximal",
                                                                        "little_intermediate",
                                                                        "little_distal",
                                                                        "little_tip"};
  return kNames[static_cast<std::size_t>(joint)];
}

std::optional<HandJoint> joint_parent(HandJoint joint) {
  const int j = static_cast<int>(joint);
  if (j <= static_cast<int>(HandJoint::kWrist)) return std::nullopt;
  // Metacarpals hang from the wrist; every other joint from the one before it in its finger.
  const bool metacarpal = j == 2 || (j >= 6 && (j - 6) % 5 == 0);
  return metacarpal ? HandJoint::kWrist : static_cast<HandJoint>(j - 1);
}

HandPose reference_open_hand(HandSide side) {
  HandPose pose;
  // Right hand, palm down, fingers along -Z, thumb toward -X. Each finger: metacarpal base, then
  // the knuckle (proximal), middle and end joints and the tip, drooping a little (y falls).
  const std::array<Eigen::Vector3d, kHandJointCount> right{
      Eigen::Vector3d(-0.004, 0.000, -0.050),  // palm: middle of the middle metacarpal
      Eigen::Vector3d(0.000, 0.000, 0.000),    // wrist
      Eigen::Vector3d(-0.022, -0.010, -0.018), Eigen::Vector3d(-0.042, -0.016, -0.042), Eigen::Vector3d(-0.056, -0.020, -0.068),
      Eigen::Vector3d(-0.064, -0.022, -0.090), Eigen::Vector3d(-0.012, 0.000, -0.010),  Eigen::Vector3d(-0.026, 0.000, -0.090),
      Eigen::Vector3d(-0.030, -0.008, -0.128), Eigen::Vector3d(-0.032, -0.016, -0.150), Eigen::Vector3d(-0.033, -0.022, -0.168),
      Eigen::Vector3d(-0.002, 0.000, -0.010),  Eigen::Vector3d(-0.006, 0.000, -0.095),  Eigen::Vector3d(-0.007, -0.009, -0.138),
      Eigen::Vector3d(-0.008, -0.018, -0.163), Eigen::Vector3d(-0.008, -0.025, -0.182), Eigen::Vector3d(0.008, 0.000, -0.010),
      Eigen::Vector3d(0.013, -0.002, -0.090),  Eigen::Vector3d(0.017, -0.011, -0.129),  Eigen::Vector3d(0.019, -0.019, -0.152),
      Eigen::Vector3d(0.020, -0.025, -0.169),  Eigen::Vector3d(0.016, -0.002, -0.012),  Eigen::Vector3d(0.031, -0.006, -0.080),
      Eigen::Vector3d(0.037, -0.013, -0.108),  Eigen::Vector3d(0.040, -0.019, -0.125),  Eigen::Vector3d(0.042, -0.024, -0.140)};
  const std::array<double, kHandJointCount> radius{0.012, 0.018,                        // palm, wrist
                                                   0.016, 0.012, 0.010, 0.008,          // thumb
                                                   0.012, 0.010, 0.009, 0.008, 0.007,   // index
                                                   0.012, 0.010, 0.009, 0.008, 0.007,   // middle
                                                   0.012, 0.010, 0.009, 0.008, 0.007,   // ring
                                                   0.012, 0.009, 0.008, 0.007, 0.006};  // little
  const double mirror = side == HandSide::kRight ? 1.0 : -1.0;
  for (int j = 0; j < kHandJointCount; ++j) {
    pose.position_m[j] = Eigen::Vector3d(mirror * right[j].x(), right[j].y(), right[j].z());
    pose.radius_m[j] = radius[j];
  }
  return pose;
}

}  // namespace rhot
