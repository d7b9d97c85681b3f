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
  CameraIntrinsics intrinsics_;
  Eigen::Matrix3d rotation_;  // cam_from_world
  Eigen::Vector3d translation_;
  Eigen::Vector3d centre_world_;
};

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
