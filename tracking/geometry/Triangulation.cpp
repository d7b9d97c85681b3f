#include "tracking/geometry/Triangulation.h"
#include "tracking/core/Solvers.h"

#include <algorithm>
#include <array>
#include <cmath>

#include <Eigen/LU>

namespace rhot {

std::optional<Eigen::Vector3d> triangulate_linear_normalised(const CameraRig& rig, std::span<const int> cameras,
                                                             std::span<const Eigen::Vector2d> normalised) {
  if (cameras.size() < 2 || cameras.size() != normalised.size()) return std::nullopt;
  // Each observation (x, y) of P = [R | t] gives x P3 - P1 = 0 and y P3 - P2 = 0 on the
  // homogeneous point. Accumulate A^T A (4x4) and take its smallest eigenvector.
  Eigen::Matrix4d ata = Eigen::Matrix4d::Zero();
  for (std::size_t i = 0; i < cameras.size(); ++i) {
    const Camera& c = rig.cameras[static_cast<std::size_t>(cameras[i])];
    Eigen::Matrix<double, 3, 4> p;
    p.leftCols<3>() = c.cam_from_world.rotation.toRotationMatrix();
    p.col(3) = c.cam_from_world.translation;
    const Eigen::RowVector4d r1 = normalised[i].x() * p.row(2) - p.row(0);
    const Eigen::RowVector4d r2 = normalised[i].y() * p.row(2) - p.row(1);
    // Rows normalised so every camera weighs alike whatever its distance.
    ata += r1.transpose() * r1 / r1.squaredNorm() + r2.transpose() * r2 / r2.squaredNorm();
  }
  const SymmetricEigen4 solver = symmetric_eigen(ata);
  const Eigen::Vector4d h = solver.vectors.col(0);
  // Degenerate: the two smallest eigenvalues are (nearly) equal, or the point is at infinity.
  if (solver.values(1) < 1e-12 * solver.values(3) || std::abs(h.w()) < 1e-12) return std::nullopt;
  const Eigen::Vector3d x = h.head<3>() / h.w();
  for (const int c : cameras) {
    if (!((rig.cameras[static_cast<std::size_t>(c)].cam_from_world * x).z() > 0.0)) return std::nullopt;
  }
  return x;
}

std::optional<Eigen::Vector3d> triangulate_linear(const CameraRig& rig, std::span<const Observation> observations) {
  std::vector<int> cameras;
  std::vector<Eigen::Vector2d> normalised;
  for (const Observation& o : observations) {
    cameras.push_back(o.camera);
    normalised.push_back(rig.cameras[static_cast<std::size_t>(o.camera)].undistort(o.pixel));
  }
  return triangulate_linear_normalised(rig, cameras, normalised);
}

std::optional<TriangulatedPoint> triangulate(const CameraRig& rig, std::span<const Observation> observations, int max_iterations) {
  const auto linear = triangulate_linear(rig, observations);
  if (!linear) return std::nullopt;
  return refine_point(rig, observations, *linear, max_iterations);
}

std::optional<TriangulatedPoint> refine_point(const CameraRig& rig, std::span<const Observation> observations,
                                              const Eigen::Vector3d& initial_world, int max_iterations) {
  return refine_point(camera_projections(rig), observations, initial_world, max_iterations);
}

std::optional<TriangulatedPoint> refine_point(std::span<const CameraProjection> cameras, std::span<const Observation> observations,
                                              const Eigen::Vector3d& initial_world, int max_iterations) {
  TriangulatedPoint out;
  if (!refine_point_into(cameras, observations, initial_world, max_iterations, out)) return std::nullopt;
  return out;
}

bool refine_point_into(std::span<const CameraProjection> cameras, std::span<const Observation> observations,
                       const Eigen::Vector3d& initial_world, int max_iterations, TriangulatedPoint& out) {
  if (observations.size() < 2) return false;
  // A step that moves every observation's projection by less than this (pixels) is taken without
  // projecting again: the residuals at the point it reaches are those of the last pass less the
  // Jacobian times the step, correct to about the square of this over the focal length (1e-4 px).
  // The point is then short of the optimum by Gauss-Newton's error after the step: of the step's
  // square over the distance to the cameras, plus the residuals over the focal length times the
  // step (a micrometre or two for 0.5-1 px of noise; Triangulation.RefinementEndsAtTheOptimum-
  // WithTheResidualsItReports measures both). From a start within a millimetre of the optimum (the
  // matcher's, where three views or more meet) that is a refinement of one pass. The point's sigma
  // is the one at the point before the step. Decided in pixels, not metres, so that it means the
  // same for a rig of any scale.
  constexpr double kLinearisedStep_px = 0.5;
  constexpr std::size_t kLinearisedUpTo = 64;  // observations whose pass is kept for it (on the stack)
  const bool linearise = observations.size() <= kLinearisedUpTo;
  std::array<Eigen::Matrix<double, 2, 3>, kLinearisedUpTo> jacobians;
  std::array<Eigen::Vector2d, kLinearisedUpTo> residuals;
  Eigen::Vector3d position = initial_world;  // a copy: initial_world may be out's
  double max_residual_px = 0.0;
  int worst_observation = 0;
  double rms_px = 0.0;
  double sigma_m_per_px = 0.0;
  Eigen::Matrix<double, 2, 3> j;
  // The largest residual, its observation and the RMS, from each observation's squared residual.
  const auto summarise = [&](auto&& squared_residual) {
    double sum = 0.0;
    max_residual_px = 0.0;
    for (std::size_t k = 0; k < observations.size(); ++k) {
      const double r2 = squared_residual(k);
      sum += r2;
      if (r2 > max_residual_px) {
        max_residual_px = r2;
        worst_observation = static_cast<int>(k);
      }
    }
    max_residual_px = std::sqrt(max_residual_px);
    rms_px = std::sqrt(sum / static_cast<double>(observations.size()));
  };
  // Each pass evaluates the residuals at the current point; all but the last also take a step.
  // A step below 1e-9 m is not taken; one below kLinearisedStep_px is, with its residuals predicted
  // as above (those reported are then the point's to about 1e-4 px; otherwise exactly).
  for (int it = 0;; ++it) {
    Eigen::Matrix3d jtj = Eigen::Matrix3d::Zero();
    Eigen::Vector3d jtr = Eigen::Vector3d::Zero();
    bool projected = true;
    summarise([&](std::size_t k) {
      const Observation& o = observations[k];
      const auto pixel = cameras[static_cast<std::size_t>(o.camera)].project(position, j);
      if (!pixel) {
        projected = false;
        return 0.0;
      }
      const Eigen::Vector2d r = o.pixel - *pixel;
      if (linearise) {
        jacobians[k] = j;
        residuals[k] = r;
      }
      jtj += j.transpose() * j;
      jtr += j.transpose() * r;
      return r.squaredNorm();
    });
    if (!projected) return false;
    Eigen::Matrix3d inverse;
    bool invertible = false;
    jtj.computeInverseWithCheck(inverse, invertible, 1e-300);
    sigma_m_per_px = invertible ? std::sqrt(std::max(inverse.trace(), 0.0) / 3.0) : 0.0;
    if (it >= max_iterations || !invertible) break;
    const Eigen::Vector3d step = inverse * jtr;
    if (!step.allFinite() || step.norm() < 1e-9) break;
    position += step;
    if (linearise) {
      double moved_px2 = 0.0;
      for (std::size_t k = 0; k < observations.size(); ++k) moved_px2 = std::max(moved_px2, (jacobians[k] * step).squaredNorm());
      if (moved_px2 < kLinearisedStep_px * kLinearisedStep_px) {
        summarise([&](std::size_t k) { return (residuals[k] - jacobians[k] * step).squaredNorm(); });
        break;
      }
    }
  }
  if (!position.allFinite() || !std::isfinite(rms_px)) return false;
  out.position_world = position;
  out.reprojection_rms_px = rms_px;
  out.max_residual_px = max_residual_px;
  out.worst_observation = worst_observation;
  out.sigma_m_per_px = sigma_m_per_px;
  out.cameras.clear();
  for (const Observation& o : observations) out.cameras.push_back(o.camera);
  return true;
}

std::optional<Eigen::Matrix3d> crlb_covariance(const CameraRig& rig, const Eigen::Vector3d& p_world, std::span<const int> cameras,
                                               double sigma_px) {
  if (cameras.size() < 2) return std::nullopt;
  Eigen::Matrix3d fisher = Eigen::Matrix3d::Zero();
  Eigen::Matrix<double, 2, 3> j;
  for (const int c : cameras) {
    if (!rig.cameras[static_cast<std::size_t>(c)].project(p_world, j)) return std::nullopt;
    fisher += j.transpose() * j;
  }
  fisher /= sigma_px * sigma_px;
  const Eigen::Vector3d values = symmetric_eigenvalues(fisher);
  if (values(0) <= 1e-12 * values(2)) return std::nullopt;
  return fisher.inverse();
}

}  // namespace rhot
