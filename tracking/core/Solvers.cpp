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
  return Eigen::umeyama(from, to, with_scale);
}

Eigen::Quaterniond rotation_between(const Eigen::Vector3d& from, const Eigen::Vector3d& to) {
  return Eigen::Quaterniond::FromTwoVectors(from, to);
}

}  // namespace rhot
