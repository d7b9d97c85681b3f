#include "tracking/sim/HandMotions.h"

#include <cmath>
#include <numbers>

#include <Eigen/Geometry>

namespace rhot {

namespace {

constexpr std::array<std::string_view, 6> kNames{"open", "fist", "pinch", "wave", "power-grasp", "precision-grasp"};

FingerAngles angles(double abduction, double mcp, double pip, double dip) { return FingerAngles{abduction, {mcp, pip, dip}}; }

}  // namespace

std::span<const std::string_view> hand_motion_names() { return kNames; }

HandPose hand_pose_from_angles(const HandPose& skeleton, const std::array<FingerChain, kFingerCount>& chains,
                               const std::array<FingerAngles, kFingerCount>& a) {
  HandPose pose = skeleton;
  for (int f = 0; f < kFingerCount; ++f) {
    const auto joints = chain_joints(static_cast<Finger>(f));
    const auto p = finger_forward(chains[static_cast<std::size_t>(f)], a[static_cast<std::size_t>(f)]);
    for (std::size_t k = 0; k < 4; ++k) pose.position_m[static_cast<std::size_t>(joints[k])] = p[k];
  }
  return pose;
}

std::optional<HandMotionFrame> hand_motion(std::string_view name, double t, const std::array<FingerChain, kFingerCount>& chains,
                                           const std::array<FingerAngles, kFingerCount>& relaxed, const Eigen::Vector3d& centre) {
  std::array<FingerAngles, kFingerCount> target = relaxed;
  double wave = 0.0;
  if (name == "open") {
    target = {angles(0.0, 0.0, 0.0, 0.0), angles(-0.2, 0.05, 0.05, 0.03), angles(0.0, 0.05, 0.05, 0.03), angles(0.15, 0.05, 0.05, 0.03),
              angles(0.25, 0.05, 0.05, 0.03)};
  } else if (name == "fist") {
    target = {angles(0.4, 0.5, 0.6, 0.6), angles(0.0, 1.4, 1.6, 1.07), angles(0.0, 1.4, 1.6, 1.07), angles(0.0, 1.4, 1.6, 1.07),
              angles(0.0, 1.4, 1.6, 1.07)};
  } else if (name == "pinch") {
    target = relaxed;
    target[0] = angles(0.55, 0.45, 0.35, 0.35);
    target[1] = angles(-0.1, 0.75, 0.85, 0.57);
  } else if (name == "wave") {
    target = {angles(0.0, 0.0, 0.0, 0.0), angles(-0.1, 0.05, 0.05, 0.03), angles(0.0, 0.05, 0.05, 0.03), angles(0.1, 0.05, 0.05, 0.03),
              angles(0.2, 0.05, 0.05, 0.03)};
    wave = 0.7 * std::sin(2.0 * std::numbers::pi * 1.0 * t);
  } else if (name == "power-grasp") {
    target = {angles(0.5, 0.35, 0.5, 0.4), angles(0.0, 0.9, 1.3, 0.87), angles(0.0, 0.9, 1.3, 0.87), angles(0.0, 0.95, 1.3, 0.87),
              angles(0.0, 1.0, 1.3, 0.87)};
  } else if (name == "precision-grasp") {
    target = relaxed;
    target[0] = angles(0.5, 0.4, 0.3, 0.2);
    target[1] = angles(-0.05, 0.55, 0.8, 0.53);
    target[2] = angles(0.0, 0.55, 0.8, 0.53);
  } else {
    return std::nullopt;
  }
  // Blend relaxed -> target -> relaxed every 2 s.
  const double s = 0.5 - 0.5 * std::cos(2.0 * std::numbers::pi * t / 2.0);
  HandMotionFrame frame;
  for (std::size_t f = 0; f < kFingerCount; ++f) {
    FingerAngles a;
    a.abduction_rad = relaxed[f].abduction_rad + s * (target[f].abduction_rad - relaxed[f].abduction_rad);
    for (std::size_t k = 0; k < 3; ++k)
      a.flexion_rad[k] = relaxed[f].flexion_rad[k] + s * (target[f].flexion_rad[k] - relaxed[f].flexion_rad[k]);
    frame.angles[f] = clamp_to_limits(chains[f].limits, a);
  }
  // The hand drifts a few centimetres, palm down, fingers forward (-Z), turning about its forearm for a wave.
  frame.world_from_hand.translation =
      centre + Eigen::Vector3d(0.05 * std::sin(0.7 * t), 0.03 * std::sin(1.1 * t + 1.0), 0.04 * std::sin(0.5 * t + 2.0));
  frame.world_from_hand.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(wave + 0.15 * std::sin(0.9 * t), Eigen::Vector3d::UnitZ()) *
                                                      Eigen::AngleAxisd(0.2 * std::sin(0.6 * t), Eigen::Vector3d::UnitX()));
  return frame;
}

}  // namespace rhot
