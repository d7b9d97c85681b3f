#include "tracking/core/Solvers.h"

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

Eigen::Vector3d symmetric_eigenvalues_direct(const Eigen::Matrix3d& m) {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver;
  solver.computeDirect(m, Eigen::EigenvaluesOnly);
  return solver.eigenvalues();
}

Svd3 svd(const Eigen::Matrix3d& m) {
  const Eigen::JacobiSVD<Eigen::Matrix3d> s(m, Eigen::ComputeFullU | Eigen::ComputeFullV);
  return {s.matrixU(), s.singularValues(), s.matrixV()};
}

}  // namespace rhot
