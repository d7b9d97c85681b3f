#pragma once
// Triangulating a marker from the cameras that see it: a linear estimate over all of them (DLT
// on undistorted coordinates), refined by Gauss-Newton on the reprojection error in pixels, which
// is the maximum-likelihood estimate under Gaussian pixel noise. And the Cramer-Rao lower bound
// on that estimate's error, the physical limit a rig and a noise level allow.

#include <optional>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "tracking/camera/Camera.h"

namespace rhot {

struct Observation {
  int camera = 0;               // index into the rig
  Eigen::Vector2d pixel{0, 0};  // distorted pixel coordinates as detected
};

struct TriangulatedPoint {
  Eigen::Vector3d position_world{0, 0, 0};
  double reprojection_rms_px = 0.0;
  double max_residual_px = 0.0;  // the largest observation's residual
  int worst_observation = 0;     // which observation (index into the observations given) that was
  std::vector<int> cameras;      // which cameras saw it
  // The point's error per axis (RMS over x, y, z, metres) per pixel of detection noise: the
  // Cramer-Rao bound sqrt(trace((J^T J)^-1) / 3) at the point. Times the pixel noise, the point's
  // uncertainty; 0 when the cameras cannot fix it.
  double sigma_m_per_px = 0.0;
};

// Linear (DLT) estimate from two or more observations, or nothing when the rays are degenerate
// (fewer than two cameras, parallel rays) or the point lands behind a camera.
std::optional<Eigen::Vector3d> triangulate_linear(const CameraRig& rig, std::span<const Observation> observations);

// The same from undistorted normalised image coordinates already at hand (cameras[i] saw
// normalised[i]); skips the undistortion.
std::optional<Eigen::Vector3d> triangulate_linear_normalised(const CameraRig& rig, std::span<const int> cameras,
                                                             std::span<const Eigen::Vector2d> normalised);

// Gauss-Newton on the pixel reprojection error from an initial estimate (at most
// `max_iterations` steps; stops when a step is below 1e-9 m, or after a step that moves no
// projection by 0.5 px or more, whose residuals are then the last pass's moved by the Jacobian:
// measured, the point within a few micrometres of the optimum and the residuals reported within
// about 1e-4 px of those there).
std::optional<TriangulatedPoint> refine_point(const CameraRig& rig, std::span<const Observation> observations,
                                              const Eigen::Vector3d& initial_world, int max_iterations = 10);
// The same with the rig's cameras prepared (camera_projections(rig)), for code that refines many points.
std::optional<TriangulatedPoint> refine_point(std::span<const CameraProjection> cameras, std::span<const Observation> observations,
                                              const Eigen::Vector3d& initial_world, int max_iterations = 10);
// The same into `out`, written only when the refinement succeeds (returns true); its storage is
// kept, so refining into one point over and over allocates nothing. initial_world may be out's own
// position.
bool refine_point_into(std::span<const CameraProjection> cameras, std::span<const Observation> observations,
                       const Eigen::Vector3d& initial_world, int max_iterations, TriangulatedPoint& out);

// Linear estimate refined by Gauss-Newton on the pixel reprojection error.
std::optional<TriangulatedPoint> triangulate(const CameraRig& rig, std::span<const Observation> observations, int max_iterations = 10);

// Covariance lower bound (m^2) of any unbiased estimate of a point seen by `cameras` with
// independent Gaussian pixel noise of sigma_px per axis: the inverse Fisher information
// sigma^2 (sum J_i^T J_i)^-1 from the projection Jacobians. Nothing if the cameras cannot fix the
// point (fewer than two, or all on one ray).
std::optional<Eigen::Matrix3d> crlb_covariance(const CameraRig& rig, const Eigen::Vector3d& p_world, std::span<const int> cameras,
                                               double sigma_px);

}  // namespace rhot
