#include "tracking/camera/Camera.h"

#include <cmath>

#include <Eigen/Geometry>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>

namespace rhot {

Eigen::Vector2d distort_normalised(const std::array<double, 5>& k, const Eigen::Vector2d& xy) {
  return camera_detail::distort(k, xy, nullptr);
}

std::optional<Eigen::Vector2d> undistort_normalised(const std::array<double, 5>& k, const Eigen::Vector2d& distorted) {
  if (!distorted.allFinite()) return std::nullopt;
  const double k1 = k[0], k2 = k[1], p1 = k[2], p2 = k[3], k3 = k[4];
  const double u = distorted.x();
  const double v = distorted.y();
  // From the distorted point with the radial factor there divided out: the radial part undone to
  // first order, a Newton step or two fewer than from the distorted point itself.
  const double r2_distorted = u * u + v * v;
  const double radial_start = 1.0 + r2_distorted * (k1 + r2_distorted * (k2 + r2_distorted * k3));
  double x = radial_start > 0.5 ? u / radial_start : u;
  double y = radial_start > 0.5 ? v / radial_start : v;
  // Newton's method on distort(x, y) = (u, v), written out (distort's model and its Jacobian).
  for (int step = 0; step < 20; ++step) {
    const double r2 = x * x + y * y;
    const double radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
    const double d = k1 + r2 * (2.0 * k2 + 3.0 * k3 * r2);  // d(radial)/d(r2)
    const double ex = x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x) - u;
    const double ey = y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y - v;
    const double j00 = radial + 2.0 * x * x * d + 2.0 * p1 * y + 6.0 * p2 * x;
    const double j01 = 2.0 * x * y * d + 2.0 * p1 * x + 2.0 * p2 * y;
    const double j11 = radial + 2.0 * y * y * d + 6.0 * p1 * y + 2.0 * p2 * x;
    const double det = j00 * j11 - j01 * j01;
    if (!(det > 1e-9 && j00 > 0.0 && j11 > 0.0)) return std::nullopt;
    if (ex * ex + ey * ey < 1e-28) return Eigen::Vector2d(x, y);
    const double sx = (j11 * ex - j01 * ey) / det;
    const double sy = (j00 * ey - j01 * ex) / det;
    x -= sx;
    y -= sy;
    if (!std::isfinite(x) || !std::isfinite(y) || x * x + y * y > 1e6) return std::nullopt;
    // After a step below 1e-8 the error is of the step's square times the model's curvature
    // (order one for any lens that does not fold): below 1e-15 without evaluating it again.
    if (sx * sx + sy * sy < 1e-16) return Eigen::Vector2d(x, y);
  }
  return std::nullopt;
}

std::optional<Eigen::Vector2d> Camera::project(const Eigen::Vector3d& p_world) const { return CameraProjection(*this).project(p_world); }

std::optional<Eigen::Vector2d> Camera::project(const Eigen::Vector3d& p_world, Eigen::Matrix<double, 2, 3>& jacobian) const {
  return CameraProjection(*this).project(p_world, jacobian);
}

bool Camera::in_image(const Eigen::Vector2d& pixel) const { return camera_detail::inside_sensor(intrinsics, pixel); }

CameraProjection::CameraProjection(const Camera& camera)
    : intrinsics_(camera.intrinsics),
      rotation_(camera.cam_from_world.rotation.toRotationMatrix()),
      translation_(camera.cam_from_world.translation),
      centre_world_(-(rotation_.transpose() * translation_)) {}

Eigen::Vector3d CameraProjection::ray_direction_world(const Eigen::Vector2d& normalised) const {
  return rotation_.transpose() * normalised.homogeneous();
}

Eigen::Vector3d axes_meeting_point(const CameraRig& rig) {
  Eigen::Matrix3d a = Eigen::Matrix3d::Zero();
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
  for (const Camera& c : rig.cameras) {
    const Eigen::Vector3d o = c.centre_world();
    const Eigen::Vector3d d = c.cam_from_world.rotation.conjugate() * Eigen::Vector3d::UnitZ();
    const Eigen::Matrix3d p = Eigen::Matrix3d::Identity() - d * d.transpose();
    a += p;
    b += p * o;
  }
  return a.ldlt().solve(b);
}

std::vector<CameraProjection> camera_projections(const CameraRig& rig) {
  std::vector<CameraProjection> out;
  out.reserve(rig.cameras.size());
  for (const Camera& c : rig.cameras) out.emplace_back(c);
  return out;
}

Eigen::Vector2d Camera::undistort(const Eigen::Vector2d& pixel) const {
  const cv::Matx33d k(intrinsics.fx, 0.0, intrinsics.cx, 0.0, intrinsics.fy, intrinsics.cy, 0.0, 0.0, 1.0);
  const cv::Vec<double, 5> dist(intrinsics.distortion[0], intrinsics.distortion[1], intrinsics.distortion[2], intrinsics.distortion[3],
                                intrinsics.distortion[4]);
  const std::vector<cv::Point2d> in{{pixel.x(), pixel.y()}};
  std::vector<cv::Point2d> out;
  // OpenCV's default stops after 5 fixed-point steps, too few for wide lenses; iterate to 1e-14.
  cv::undistortPoints(in, out, k, dist, cv::noArray(), cv::noArray(),
                      cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 100, 1e-14));
  return {out[0].x, out[0].y};
}

Eigen::Vector3d Camera::centre_world() const { return cam_from_world.inverse().translation; }

Eigen::Vector3d Camera::ray_world(const Eigen::Vector2d& pixel) const {
  const Eigen::Vector2d xy = undistort(pixel);
  return (cam_from_world.rotation.conjugate() * Eigen::Vector3d(xy.x(), xy.y(), 1.0)).normalized();
}

Rigid3d cam_from_world_look_at(const Eigen::Vector3d& position, const Eigen::Vector3d& target) {
  const Eigen::Vector3d z = (target - position).normalized();  // forward
  // Up in the image is world +Y, or world +Z where the camera looks (nearly) straight down or up.
  const Eigen::Vector3d reference = std::abs(z.y()) > 0.99 ? Eigen::Vector3d::UnitZ() : Eigen::Vector3d::UnitY();
  const Eigen::Vector3d x = z.cross(reference).normalized();  // right
  const Eigen::Vector3d y = z.cross(x);                       // down in the image
  Eigen::Matrix3d world_from_cam_rotation;
  world_from_cam_rotation.col(0) = x;
  world_from_cam_rotation.col(1) = y;
  world_from_cam_rotation.col(2) = z;
  Rigid3d world_from_cam;
  world_from_cam.rotation = Eigen::Quaterniond(world_from_cam_rotation).normalized();
  world_from_cam.translation = position;
  return world_from_cam.inverse();
}

}  // namespace rhot
