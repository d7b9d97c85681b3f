#pragma once
// Eigen's small dense decompositions, compiled once (Solvers.cpp) instead of in every file that
// uses one: each instantiation of SelfAdjointEigenSolver or JacobiSVD costs tens of seconds of
// compile time under the sanitizers (docs/PERFORMANCE.md, "Build time"). Each function is the
// Eigen call its name says, with the same results bit for bit, except the closed-form eigenvalues
// (symmetric_eigenvalues_direct and _packed) and umeyama_transform, which are rhot's own code.

#include <array>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace rhot {

// SelfAdjointEigenSolver::compute (the iterative QL algorithm): eigenvalues ascending, the
// eigenvectors as the matching columns.
struct SymmetricEigen3 {
  Eigen::Vector3d values;
  Eigen::Matrix3d vectors;
};
struct SymmetricEigen4 {
  Eigen::Vector4d values;
  Eigen::Matrix4d vectors;
};
SymmetricEigen3 symmetric_eigen(const Eigen::Matrix3d& m);
SymmetricEigen4 symmetric_eigen(const Eigen::Matrix4d& m);
// The eigenvalues alone (ascending): compute(m, EigenvaluesOnly).
Eigen::Vector3d symmetric_eigenvalues(const Eigen::Matrix3d& m);
// The closed-form solver for 3 x 3 (the algorithm of computeDirect(m, EigenvaluesOnly), ascending):
// faster, a little less accurate for badly scaled matrices. The packed form takes the upper
// triangle row by row (m00, m01, m02, m11, m12, m22).
Eigen::Vector3d symmetric_eigenvalues_direct(const Eigen::Matrix3d& m);
std::array<double, 3> symmetric_eigenvalues_packed(const std::array<double, 6>& upper);

// JacobiSVD with full U and V: m = U diag(singular_values) V^T, singular values descending.
struct Svd3 {
  Eigen::Matrix3d u;
  Eigen::Vector3d singular_values;
  Eigen::Matrix3d v;
};
Svd3 svd(const Eigen::Matrix3d& m);

// Quaterniond::FromTwoVectors(from, to): the smallest rotation taking from's direction to to's
// (for opposite directions, a half turn about an axis found by a 2 x 3 JacobiSVD). Each expression
// type it is called with instantiates that SVD anew: 6 s of compile time per call site under the
// sanitizers, measured in engine_physics_test's unit.
Eigen::Quaterniond rotation_between(const Eigen::Vector3d& from, const Eigen::Vector3d& to);

// The similarity (4 x 4, homogeneous; a rigid motion without the scale) taking the columns of
// `from` nearest the columns of `to` in least squares: Umeyama's algorithm, as Eigen::umeyama
// (from, to, with_scale) computes it, equal to it to rounding (not bit for bit: its sums are in
// another order). Eigen's 3 x 3 SVD made it the costliest call to compile of tracking/hand's and
// tracking/calib's units, and its products of 3 x n matrices the costliest of this one's.
Eigen::Matrix4d umeyama_transform(const Eigen::Matrix3Xd& from, const Eigen::Matrix3Xd& to, bool with_scale);

}  // namespace rhot
