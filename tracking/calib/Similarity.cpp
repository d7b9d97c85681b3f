#include "tracking/calib/Similarity.h"
#include "tracking/core/Solvers.h"

#include <cmath>

#include <Eigen/Geometry>

namespace rhot {

Similarity3 Similarity3::inverse() const {
  Similarity3 inv;
  inv.scale = 1.0 / scale;
  inv.rotation = rotation.transpose();
  inv.translation = -inv.scale * (inv.rotation * translation);
  return inv;
}

std::optional<Similarity3> fit_similarity(const std::vector<Eigen::Vector3d>& from, const std::vector<Eigen::Vector3d>& to,
                                          bool with_scale) {
  if (from.size() != to.size() || from.size() < 3) return std::nullopt;
  const auto n = static_cast<Eigen::Index>(from.size());
  Eigen::Matrix3Xd a(3, n), b(3, n);
  for (Eigen::Index i = 0; i < n; ++i) {
    if (!from[static_cast<std::size_t>(i)].allFinite() || !to[static_cast<std::size_t>(i)].allFinite()) return std::nullopt;
    a.col(i) = from[static_cast<std::size_t>(i)];
    b.col(i) = to[static_cast<std::size_t>(i)];
  }
  // Collinear points leave the rotation about their line free: their spread's second axis is nil.
  const Eigen::Matrix3Xd centred = a.colwise() - a.rowwise().mean();
  const Eigen::Vector3d ev = symmetric_eigenvalues(centred * centred.transpose());  // ascending: squared singular values
  if (!(ev[1] > 1e-18 * std::max(ev[2], 1e-300))) return std::nullopt;
  const Eigen::Matrix4d m = umeyama_transform(a, b, with_scale);
  if (!m.allFinite()) return std::nullopt;
  Similarity3 s;
  s.scale = with_scale ? m.block<3, 3>(0, 0).col(0).norm() : 1.0;
  if (!(s.scale > 1e-12) || !std::isfinite(s.scale)) return std::nullopt;  // `to` all in one place
  s.rotation = m.block<3, 3>(0, 0) / s.scale;
  s.translation = m.block<3, 1>(0, 3);
  if (!s.rotation.allFinite() || !s.translation.allFinite()) return std::nullopt;
  return s;
}

TrackingVolume transform_volume(const TrackingVolume& volume, const Similarity3& new_from_old) {
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300), hi = Eigen::Vector3d::Constant(-1e300);
  for (int corner = 0; corner < 8; ++corner) {
    const Eigen::Vector3d sign((corner & 1) ? 0.5 : -0.5, (corner & 2) ? 0.5 : -0.5, (corner & 4) ? 0.5 : -0.5);
    const Eigen::Vector3d p = new_from_old.apply(volume.centre_m + sign.cwiseProduct(volume.size_m));
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  return TrackingVolume{(lo + hi) / 2, hi - lo};
}

Camera transform_camera(const Camera& camera, const Similarity3& new_from_old) {
  // x_cam = R_c x_old + t_c and x_old = (R^T (x_new - t)) / s; the camera frame scales with the
  // scene, so x_cam' = s x_cam = R_c R^T x_new + (s t_c - R_c R^T t).
  Camera out = camera;
  const Eigen::Matrix3d rc = camera.cam_from_world.rotation.toRotationMatrix();
  const Eigen::Matrix3d r = rc * new_from_old.rotation.transpose();
  out.cam_from_world.rotation = Eigen::Quaterniond(r).normalized();
  out.cam_from_world.translation = new_from_old.scale * camera.cam_from_world.translation - r * new_from_old.translation;
  return out;
}

}  // namespace rhot
