#include "tracking/core/Solvers.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>

namespace rhot {

SymmetricEigen3 symmetric_eigen(const Eigen::Matrix3d& m) {
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(m);
  return {solver.eigenvalues(), solver.eigenvectors()};
}

SymmetricEigen4 symmetric_eigen(const Eigen::Matrix4d& m) {
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d> solver(m);
  return {solver.eigenvalues(), solver.eigenvectors()};
}

Eigen::Vector3d symmetric_eigenvalues(const Eigen::Matrix3d& m) {
  return Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(m, Eigen::EigenvaluesOnly).eigenvalues();
}

std::array<double, 3> symmetric_eigenvalues_packed(const std::array<double, 6>& upper) {
  // The trigonometric solution of the characteristic cubic (O. K. Smith, 1961), on the matrix
  // shifted by its mean eigenvalue and scaled to unit largest entry so that the cubic's
  // coefficients neither overflow nor lose the small eigenvalues. The same algorithm as Eigen's
  // computeDirect, in scalars: Eigen's expression templates are not inlined at the sanitized
  // build's -O1, and the rig planner calls this for every grid point of every candidate tried.
  const double shift = (upper[0] + upper[3] + upper[5]) / 3.0;
  double a00 = upper[0] - shift, a01 = upper[1], a02 = upper[2], a11 = upper[3] - shift, a12 = upper[4], a22 = upper[5] - shift;
  const double scale = std::max({std::abs(a00), std::abs(a01), std::abs(a02), std::abs(a11), std::abs(a12), std::abs(a22)});
  // NaN or infinity in: NaN out, as from the iterative solver (std::max passes over a NaN).
  if (!std::isfinite(upper[0] + upper[1] + upper[2] + upper[3] + upper[4] + upper[5] + scale)) {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    return {nan, nan, nan};
  }
  if (scale == 0.0) return {shift, shift, shift};  // a multiple of the identity
  for (double* v : {&a00, &a01, &a02, &a11, &a12, &a22}) *v /= scale;
  // det(A - x I) = -x^3 + c2 x^2 - c1 x + c0.
  const double c0 = a00 * a11 * a22 + 2.0 * a01 * a02 * a12 - a00 * a12 * a12 - a11 * a02 * a02 - a22 * a01 * a01;
  const double c1 = a00 * a11 - a01 * a01 + a00 * a22 - a02 * a02 + a11 * a22 - a12 * a12;
  const double c2_over_3 = (a00 + a11 + a22) / 3.0;
  const double a_over_3 = std::max((3.0 * c2_over_3 * c2_over_3 - c1) / 3.0, 0.0);
  const double half_b = 0.5 * (c0 + c2_over_3 * (2.0 * c2_over_3 * c2_over_3 - c1));
  const double q = std::max(a_over_3 * a_over_3 * a_over_3 - half_b * half_b, 0.0);
  const double rho = std::sqrt(a_over_3);
  const double theta = std::atan2(std::sqrt(q), half_b) / 3.0;  // in [0, pi/3]: the roots ascend
  const double cos_theta = std::cos(theta), sin_theta = std::sin(theta);
  const double sqrt3 = std::sqrt(3.0);
  return {(c2_over_3 - rho * (cos_theta + sqrt3 * sin_theta)) * scale + shift,
          (c2_over_3 - rho * (cos_theta - sqrt3 * sin_theta)) * scale + shift, (c2_over_3 + 2.0 * rho * cos_theta) * scale + shift};
}

Eigen::Vector3d symmetric_eigenvalues_direct(const Eigen::Matrix3d& m) {
  const std::array<double, 3> v = symmetric_eigenvalues_packed({m(0, 0), m(0, 1), m(0, 2), m(1, 1), m(1, 2), m(2, 2)});
  return {v[0], v[1], v[2]};
}

Svd3 svd(const Eigen::Matrix3d& m) {
  const Eigen::JacobiSVD<Eigen::Matrix3d> s(m, Eigen::ComputeFullU | Eigen::ComputeFullV);
  return {s.matrixU(), s.singularValues(), s.matrixV()};
}

Eigen::Matrix4d umeyama_transform(const Eigen::Matrix3Xd& from, const Eigen::Matrix3Xd& to, bool with_scale) {
  // Umeyama (1991), as Eigen::umeyama computes it, in fixed-size sums over the columns: Eigen's
  // products of the two 3 x n matrices instantiate its general matrix-product kernels, most of this
  // file's compile time under the sanitizers.
  const Eigen::Index n = from.cols();
  const double inv_n = 1.0 / static_cast<double>(n);
  Eigen::Vector3d mean_from = Eigen::Vector3d::Zero(), mean_to = Eigen::Vector3d::Zero();
  for (Eigen::Index i = 0; i < n; ++i) {
    mean_from += from.col(i);
    mean_to += to.col(i);
  }
  mean_from *= inv_n;
  mean_to *= inv_n;
  Eigen::Matrix3d sigma = Eigen::Matrix3d::Zero();  // the cross-covariance, to x from^T
  double from_variance = 0.0;
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::Vector3d f = from.col(i) - mean_from;
    sigma.noalias() += (to.col(i) - mean_to) * f.transpose();
    from_variance += f.squaredNorm();
  }
  sigma *= inv_n;
  from_variance *= inv_n;
  const Svd3 s = svd(sigma);
  // A reflection is the best orthogonal fit when det(U) det(V) < 0: the rotation nearest it flips
  // the axis of the smallest singular value.
  Eigen::Vector3d d = Eigen::Vector3d::Ones();
  if (s.u.determinant() * s.v.determinant() < 0.0) d(2) = -1.0;
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  const Eigen::Matrix3d r = s.u * d.asDiagonal() * s.v.transpose();
  const double c = with_scale ? s.singular_values.dot(d) / from_variance : 1.0;
  m.topLeftCorner<3, 3>() = c * r;
  m.topRightCorner<3, 1>() = mean_to - c * r * mean_from;
  return m;
}

Eigen::Quaterniond rotation_between(const Eigen::Vector3d& from, const Eigen::Vector3d& to) {
  return Eigen::Quaterniond::FromTwoVectors(from, to);
}

}  // namespace rhot
