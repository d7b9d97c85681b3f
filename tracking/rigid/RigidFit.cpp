#include "tracking/rigid/RigidFit.h"
#include "tracking/core/Solvers.h"

#include <cmath>
#include <limits>

#include <Eigen/Cholesky>
#include <Eigen/Geometry>

namespace rhot {

std::optional<RigidFit> fit_rigid(std::span<const Eigen::Vector3d> from, std::span<const Eigen::Vector3d> to,
                                  std::span<const double> weight) {
  const std::size_t n = from.size();
  if (to.size() != n || n < 3 || (!weight.empty() && weight.size() != n)) return std::nullopt;
  const auto w = [&](std::size_t i) { return weight.empty() ? 1.0 : weight[i]; };
  Eigen::Vector3d mean_a = Eigen::Vector3d::Zero(), mean_b = Eigen::Vector3d::Zero();
  double sum_w = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    if (!from[i].allFinite() || !to[i].allFinite() || !(w(i) > 0.0) || !std::isfinite(w(i))) return std::nullopt;
    mean_a += w(i) * from[i];
    mean_b += w(i) * to[i];
    sum_w += w(i);
  }
  mean_a /= sum_w;
  mean_b /= sum_w;
  Eigen::Matrix3d spread_a = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d cross = Eigen::Matrix3d::Zero();  // sum (a - mean_a)(b - mean_b)^T
  double var_a = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d a = from[i] - mean_a;
    const Eigen::Vector3d b = to[i] - mean_b;
    spread_a += w(i) * a * a.transpose();
    cross += w(i) * a * b.transpose();
    var_a += w(i) * a.squaredNorm();
  }
  // Collinear points leave the rotation about their line free.
  const Eigen::Vector3d spread_values = symmetric_eigenvalues_direct(spread_a);
  if (!(spread_values(1) > 1e-10 * std::max(spread_values(2), 1e-30))) return std::nullopt;

  // Kabsch: the rotation maximising trace(R^T H^T), with the reflection case turned into a rotation.
  const Svd3 decomposed = svd(cross);
  Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
  if ((decomposed.v * decomposed.u.transpose()).determinant() < 0.0) d(2, 2) = -1.0;
  const Eigen::Matrix3d r = decomposed.v * d * decomposed.u.transpose();
  RigidFit fit;
  fit.to_from_from.rotation = Eigen::Quaterniond(r).normalized();
  fit.to_from_from.translation = mean_b - r * mean_a;
  // The similarity fit's scale (Umeyama): sum of the signed singular values over the spread of `from`.
  fit.scale = (decomposed.singular_values.array() * d.diagonal().array()).sum() / var_a;
  double sum = 0.0;
  for (std::size_t i = 0; i < n; ++i) sum += (fit.to_from_from * from[i] - to[i]).squaredNorm();
  fit.rms_m = std::sqrt(sum / static_cast<double>(n));
  if (!fit.to_from_from.is_finite() || !std::isfinite(fit.rms_m) || !std::isfinite(fit.scale)) return std::nullopt;
  return fit;
}

}  // namespace rhot

namespace rhot {

Matrix6d rigid_fit_covariance(const Rigid3d& to_from_from, std::span<const Eigen::Vector3d> from, std::span<const double> sigma_m) {
  Matrix6d information = Matrix6d::Zero();
  for (std::size_t i = 0; i < from.size(); ++i) {
    const double sigma = sigma_m.size() == from.size() ? sigma_m[i] : 0.001;
    const Eigen::Vector3d r = to_from_from.rotation * from[i];
    Eigen::Matrix<double, 3, 6> j;
    j.leftCols<3>().setIdentity();
    j.rightCols<3>() << 0, r.z(), -r.y(), -r.z(), 0, r.x(), r.y(), -r.x(), 0;  // -[r]x
    information += j.transpose() * j / (sigma * sigma);
  }
  const Eigen::LDLT<Matrix6d> ldlt(information);
  // Points in a line leave the turn about it unmeasured: a pivot at rounding level.
  if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().minCoeff() > 1e-12 * ldlt.vectorD().maxCoeff()))
    return Matrix6d::Identity() * std::numeric_limits<double>::infinity();
  return ldlt.solve(Matrix6d::Identity());
}

}  // namespace rhot
