#include "tracking/rigid/RigidFit.h"

#include <cmath>

#include <Eigen/Geometry>
#include <Eigen/SVD>

namespace rhot {

std::optional<RigidFit> fit_rigid(std::span<const Eigen::Vector3d> from, std::span<const Eigen::Vector3d> to) {
  const auto n = static_cast<Eigen::Index>(from.size());
  if (from.size() != to.size() || n < 3) return std::nullopt;
  Eigen::Matrix3Xd a(3, n), b(3, n);
  for (Eigen::Index i = 0; i < n; ++i) {
    a.col(i) = from[static_cast<std::size_t>(i)];
    b.col(i) = to[static_cast<std::size_t>(i)];
  }
  if (!a.allFinite() || !b.allFinite()) return std::nullopt;
  // Collinear points leave the rotation about their line free.
  const Eigen::Matrix3Xd centred = a.colwise() - a.rowwise().mean();
  const Eigen::JacobiSVD<Eigen::Matrix3d> spread(centred * centred.transpose());
  const Eigen::Vector3d s = spread.singularValues();
  if (!(s(1) > 1e-10 * std::max(s(0), 1e-30))) return std::nullopt;

  const Eigen::Matrix4d similarity = Eigen::umeyama(a, b, true);
  const Eigen::Matrix4d rigid = Eigen::umeyama(a, b, false);
  RigidFit fit;
  fit.scale = similarity.topLeftCorner<3, 3>().determinant();
  fit.scale = std::cbrt(fit.scale);
  const Eigen::Matrix3d r = rigid.topLeftCorner<3, 3>();
  fit.to_from_from.rotation = Eigen::Quaterniond(r).normalized();
  fit.to_from_from.translation = rigid.topRightCorner<3, 1>();
  double sum = 0.0;
  for (Eigen::Index i = 0; i < n; ++i) sum += (fit.to_from_from * Eigen::Vector3d(a.col(i)) - b.col(i)).squaredNorm();
  fit.rms_m = std::sqrt(sum / static_cast<double>(n));
  if (!fit.to_from_from.is_finite() || !std::isfinite(fit.rms_m) || !std::isfinite(fit.scale)) return std::nullopt;
  return fit;
}

}  // namespace rhot
