#pragma once
// Pinhole cameras with OpenCV's distortion model, and rigs of them.
//
// Camera frames follow OpenCV: x right, y down, z forward (out of the lens); pixel (0, 0) is the
// centre of the top-left pixel, as in OpenCV. The world frame is rhot's (metres, +Y up, -Z
// forward). `cam_from_world` maps world points into the camera frame.

#include <array>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "tracking/core/Rigid3.h"

namespace rhot {

struct CameraIntrinsics {
  int width_px = 0;
  int height_px = 0;
  double fx = 0.0, fy = 0.0;  // focal lengths, pixels
  double cx = 0.0, cy = 0.0;  // principal point, pixels
  // OpenCV's order: k1, k2, p1, p2, k3 (radial k, tangential p).
  std::array<double, 5> distortion{0.0, 0.0, 0.0, 0.0, 0.0};
};

struct Camera {
  std::string name;
  CameraIntrinsics intrinsics;
  Rigid3d cam_from_world;

  // The pixel where a world point appears, or nothing when it is behind the camera (z <= 1 mm).
  // Does not check the image bounds (see in_image).
  std::optional<Eigen::Vector2d> project(const Eigen::Vector3d& p_world) const;
  // The same with the 2x3 Jacobian d(pixel)/d(p_world), for refinement and error bounds.
  std::optional<Eigen::Vector2d> project(const Eigen::Vector3d& p_world, Eigen::Matrix<double, 2, 3>& jacobian) const;
  bool in_image(const Eigen::Vector2d& pixel) const;

  // Distorted pixel -> undistorted normalised image coordinates (x/z, y/z), by OpenCV's iterative
  // inversion of the distortion model.
  Eigen::Vector2d undistort(const Eigen::Vector2d& pixel) const;
  // The ray through a pixel: origin (the camera centre) and unit direction, both in world coordinates.
  Eigen::Vector3d centre_world() const;
  Eigen::Vector3d ray_world(const Eigen::Vector2d& pixel) const;
};

// Normalised undistorted image coordinates -> distorted normalised coordinates (OpenCV's model).
Eigen::Vector2d distort_normalised(const std::array<double, 5>& k, const Eigen::Vector2d& xy);
// The inverse: distorted -> undistorted normalised coordinates, by Newton's method from the
// distorted point with its radial factor divided out (quadratic convergence: 1-3 steps for
// lenses like the shipped rigs', against OpenCV's fixed-point iteration, 8 times slower for the
// same 1e-13). Nothing where it does not
// converge or the model folds over (its Jacobian is not positive there).
std::optional<Eigen::Vector2d> undistort_normalised(const std::array<double, 5>& k, const Eigen::Vector2d& distorted);

// A camera prepared for projecting many points: its rotation held as a matrix, which projects
// faster than the quaternion. Copies what it needs, so it does not refer back to the camera.
class CameraProjection {
 public:
  explicit CameraProjection(const Camera& camera);

  // As Camera::project, Camera::in_image.
  std::optional<Eigen::Vector2d> project(const Eigen::Vector3d& p_world) const;
  std::optional<Eigen::Vector2d> project(const Eigen::Vector3d& p_world, Eigen::Matrix<double, 2, 3>& jacobian) const;
  bool in_image(const Eigen::Vector2d& pixel) const;
  // The camera centre and the (unnormalised) world direction of the ray through undistorted
  // normalised image coordinates.
  const Eigen::Vector3d& centre_world() const { return centre_world_; }
  Eigen::Vector3d ray_direction_world(const Eigen::Vector2d& normalised) const;

 private:
  // The point's undistorted normalised coordinates and its inverse depth, or false where it is not
  // in front of the camera (nearer than camera_detail::kMinDepth_m).
  bool to_normalised(const Eigen::Vector3d& p_world, double& x, double& y, double& inv_z) const;

  CameraIntrinsics intrinsics_;
  Eigen::Matrix3d rotation_;  // cam_from_world
  Eigen::Vector3d translation_;
  Eigen::Vector3d centre_world_;
};

namespace camera_detail {

// Nearer the camera than this (along its axis), a point does not project.
inline constexpr double kMinDepth_m = 1e-3;

// Distortion of normalised coordinates and its 2x2 Jacobian (OpenCV's model). Inlined where it is
// called, so that projection (matching's and refinement's innermost work) compiles without the
// branch and call.
[[gnu::always_inline]] inline Eigen::Vector2d distort(const std::array<double, 5>& k, const Eigen::Vector2d& xy,
                                                      Eigen::Matrix2d* jacobian) {
  const double x = xy.x();
  const double y = xy.y();
  const double k1 = k[0], k2 = k[1], p1 = k[2], p2 = k[3], k3 = k[4];
  const double r2 = x * x + y * y;
  const double radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
  const Eigen::Vector2d out(x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x),
                            y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y);
  if (jacobian != nullptr) {
    const double d = k1 + r2 * (2.0 * k2 + 3.0 * k3 * r2);  // d(radial)/d(r2)
    const double off_diagonal = 2.0 * x * y * d + 2.0 * p1 * x + 2.0 * p2 * y;
    (*jacobian)(0, 0) = radial + 2.0 * x * x * d + 2.0 * p1 * y + 6.0 * p2 * x;
    (*jacobian)(0, 1) = off_diagonal;
    (*jacobian)(1, 0) = off_diagonal;
    (*jacobian)(1, 1) = radial + 2.0 * y * y * d + 6.0 * p1 * y + 2.0 * p2 * x;
  }
  return out;
}

[[gnu::always_inline]] inline bool inside_sensor(const CameraIntrinsics& k, const Eigen::Vector2d& pixel) {
  // Pixel centres are integers, so the sensor spans [-0.5, size - 0.5).
  return pixel.x() >= -0.5 && pixel.y() >= -0.5 && pixel.x() < k.width_px - 0.5 && pixel.y() < k.height_px - 0.5;
}

}  // namespace camera_detail

[[gnu::always_inline]] inline bool CameraProjection::to_normalised(const Eigen::Vector3d& p_world, double& x, double& y,
                                                                   double& inv_z) const {
  const Eigen::Matrix3d& r = rotation_;
  const double z = r(2, 0) * p_world.x() + r(2, 1) * p_world.y() + r(2, 2) * p_world.z() + translation_.z();
  if (!(z > camera_detail::kMinDepth_m)) return false;
  inv_z = 1.0 / z;
  x = (r(0, 0) * p_world.x() + r(0, 1) * p_world.y() + r(0, 2) * p_world.z() + translation_.x()) * inv_z;
  y = (r(1, 0) * p_world.x() + r(1, 1) * p_world.y() + r(1, 2) * p_world.z() + translation_.y()) * inv_z;
  return true;
}

// Defined here, not in Camera.cpp, so that matching and refinement (their innermost work is
// projecting into camera after camera) compile them into their own loops; written out in scalars
// (Eigen's small fixed-size expressions cost about twice the instructions here). Always inlined:
// an inline function a library leaves as a call is linked to whichever copy the linker meets
// first, and in the sanitized build that is the test program's, compiled at -O0 (RhotOptions.cmake):
// the planner's tests ran three to five times longer on it (docs/PERFORMANCE.md, "Build and test
// time"). The distortion's Jacobian is written coefficient by coefficient for the same reason
// (Eigen's comma initializer is a call of its own).
[[gnu::always_inline]] inline std::optional<Eigen::Vector2d> CameraProjection::project(const Eigen::Vector3d& p_world) const {
  double x = 0.0, y = 0.0, inv_z = 0.0;
  if (!to_normalised(p_world, x, y, inv_z)) return std::nullopt;
  const Eigen::Vector2d d = camera_detail::distort(intrinsics_.distortion, Eigen::Vector2d(x, y), nullptr);
  return Eigen::Vector2d(intrinsics_.fx * d.x() + intrinsics_.cx, intrinsics_.fy * d.y() + intrinsics_.cy);
}

[[gnu::always_inline]] inline std::optional<Eigen::Vector2d> CameraProjection::project(const Eigen::Vector3d& p_world,
                                                                                       Eigen::Matrix<double, 2, 3>& jacobian) const {
  double x = 0.0, y = 0.0, inv_z = 0.0;
  if (!to_normalised(p_world, x, y, inv_z)) return std::nullopt;
  const Eigen::Matrix3d& r = rotation_;
  Eigen::Matrix2d dd;  // d(distorted)/d(x, y): symmetric
  const Eigen::Vector2d d = camera_detail::distort(intrinsics_.distortion, Eigen::Vector2d(x, y), &dd);
  // d(pixel)/d(p_world) = diag(fx, fy) * dd * d(x, y)/d(p_world), where the column m of
  // d(x, y)/d(p_world) is ((R(0, m) - x R(2, m)) / z, (R(1, m) - y R(2, m)) / z).
  const double a = intrinsics_.fx * dd(0, 0);
  const double b = intrinsics_.fx * dd(0, 1);
  const double c = intrinsics_.fy * dd(1, 0);
  const double e = intrinsics_.fy * dd(1, 1);
  for (int m = 0; m < 3; ++m) {
    const double nx = (r(0, m) - x * r(2, m)) * inv_z;
    const double ny = (r(1, m) - y * r(2, m)) * inv_z;
    jacobian(0, m) = a * nx + b * ny;
    jacobian(1, m) = c * nx + e * ny;
  }
  return Eigen::Vector2d(intrinsics_.fx * d.x() + intrinsics_.cx, intrinsics_.fy * d.y() + intrinsics_.cy);
}

[[gnu::always_inline]] inline bool CameraProjection::in_image(const Eigen::Vector2d& pixel) const {
  return camera_detail::inside_sensor(intrinsics_, pixel);
}

// The box a rig is meant to track (axis-aligned in the world, metres): where evaluation puts its
// simulated markers unless told otherwise.
struct TrackingVolume {
  Eigen::Vector3d centre_m{0, 0, 0};
  Eigen::Vector3d size_m{1, 1, 1};
};

struct CameraRig {
  std::string name;
  std::vector<Camera> cameras;
  std::optional<TrackingVolume> volume;
};

// The point nearest (least squares) to every camera's optical axis: where the rig looks.
Eigen::Vector3d axes_meeting_point(const CameraRig& rig);

// One CameraProjection per camera of the rig, in rig order.
std::vector<CameraProjection> camera_projections(const CameraRig& rig);

// A camera at `position` looking at `target`, with world +Y as "up" in the image (OpenCV frame:
// image y points away from world up); looking within about 8 degrees of straight down or up, image
// up is world +Z instead. Precondition: target != position.
Rigid3d cam_from_world_look_at(const Eigen::Vector3d& position, const Eigen::Vector3d& target);

}  // namespace rhot
