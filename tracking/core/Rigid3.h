#pragma once
// A rigid transform (rotation then translation) in metres, named by the frames it maps between:
// `Rigid3d cam_from_world` takes a point in world coordinates to camera coordinates, so
// `p_cam = cam_from_world * p_world` and `world_from_cam = cam_from_world.inverse()`.
// Composition reads right to left: `cam_from_star = cam_from_world * world_from_star`.

#include <Eigen/Geometry>

namespace rhot {

// A pose's covariance: over its position (metres) and a small rotation (radians, world frame).
using Matrix6d = Eigen::Matrix<double, 6, 6>;

struct Rigid3d {
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();  // kept unit length
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();         // metres

  static Rigid3d identity() { return {}; }

  Eigen::Vector3d operator*(const Eigen::Vector3d& point) const { return rotation * point + translation; }
  Rigid3d operator*(const Rigid3d& b_from_a) const {
    // (this = c_from_b) * b_from_a = c_from_a
    return {(rotation * b_from_a.rotation).normalized(), rotation * b_from_a.translation + translation};
  }
  Rigid3d inverse() const {
    const Eigen::Quaterniond inv = rotation.conjugate();
    return {inv, -(inv * translation)};
  }
  Eigen::Matrix4d matrix() const {
    Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
    m.topLeftCorner<3, 3>() = rotation.toRotationMatrix();
    m.topRightCorner<3, 1>() = translation;
    return m;
  }
  // False where any component is NaN or infinite: such a pose must never reach physics or rendering.
  bool is_finite() const { return rotation.coeffs().allFinite() && translation.allFinite(); }
};

}  // namespace rhot
