#pragma once
// What a rig will see and how well, before a camera is bought: over a grid through a tracking
// volume, how many cameras see each point and the 3D error to expect there.
//
// A camera sees a point when the point lies in front of it and projects inside its image (a
// clear room: nothing occludes). Where two or more cameras see a point, the error of its
// triangulation from them is predicted by the Cramer-Rao bound, C = (sum J_k^T J_k / sigma^2)^-1
// over the seeing cameras' projection Jacobians J_k and the pixel noise sigma (per axis): rhot's
// triangulation meets that bound to about 1 % (docs/PERFORMANCE.md, issue 4), so the bound is
// what a simulated or real run measures. The error's distribution over the volume is that of
// e ~ N(0, C_p) with p drawn uniformly from the covered volume; its median and 95th percentile are
// estimated by drawing `samples_per_point` errors at every grid point (fixed seed: the same rig
// gives the same figures), directly comparable to `rhot-eval triangulation`'s measured
// `error_median_mm` and `error_p95_mm`.

#include <cstdint>
#include <expected>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "tracking/camera/Camera.h"

namespace rhot {

struct CoverageSettings {
  double sigma_px = 0.3;       // detection noise per axis
  double grid_step_m = 0.0;    // spacing of the grid (about); 0: about max_points points in the volume
  int max_points = 20000;      // the grid's size when grid_step_m is 0
  int samples_per_point = 16;  // errors drawn at every covered point for the quantiles
  std::uint32_t seed = 1;
};

// The grid: the volume cut into nx x ny x nz cells of (nearly) equal sides, a point at each
// cell's centre; X fastest, then Z, then Y (height last, so that a horizontal slice is one
// contiguous run).
struct CoverageGrid {
  Eigen::Vector3d origin_m{0, 0, 0};  // the first point (lowest X, Y and Z)
  Eigen::Vector3d step_m{0.1, 0.1, 0.1};
  int nx = 0, ny = 0, nz = 0;
  std::size_t size() const { return static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny) * static_cast<std::size_t>(nz); }
  std::size_t index(int x, int y, int z) const {
    return (static_cast<std::size_t>(y) * static_cast<std::size_t>(nz) + static_cast<std::size_t>(z)) * static_cast<std::size_t>(nx) +
           static_cast<std::size_t>(x);
  }
  Eigen::Vector3d point(int x, int y, int z) const { return origin_m + step_m.cwiseProduct(Eigen::Vector3d(x, y, z)); }
};

struct CoverageReport {
  CoverageGrid grid;
  TrackingVolume volume;
  double sigma_px = 0.3;
  // Per grid point: the cameras that see it, and (seen by two or more) the predicted RMS 3D error
  // sqrt(trace C) in millimetres, else NaN.
  std::vector<int> views;
  std::vector<double> rms_error_mm;
  // Fractions of the grid's points seen by at least 1, 2 and 3 cameras.
  double coverage_1 = 0.0, coverage_2 = 0.0, coverage_3 = 0.0;
  // Over the points seen by two or more: the error's median and 95th percentile (see above), and
  // the worst point's 95th percentile bound, 2.796 sqrt(largest eigenvalue of C) (the chi-square
  // 95 % radius for three degrees of freedom along the worst axis: never below the true value).
  // All three NaN (and the worst point) when no point is seen by two cameras.
  double predicted_median_mm = 0.0;
  double predicted_p95_mm = 0.0;
  double predicted_max_mm = 0.0;
  Eigen::Vector3d worst_point_m{0, 0, 0};
};

// The cameras that see a world point (in front, inside the image), in rig order.
std::vector<int> cameras_seeing(std::span<const CameraProjection> cameras, const Eigen::Vector3d& p_world);

// The Cramer-Rao covariance (m^2) of a point triangulated from these cameras with sigma_px of
// noise per axis; nothing when fewer than two see it or their rays are (nearly) parallel there.
std::optional<Eigen::Matrix3d> predicted_covariance(std::span<const CameraProjection> cameras, std::span<const int> seeing,
                                                    const Eigen::Vector3d& p_world, double sigma_px);

// The rig's coverage of the volume. Errors name what is wrong: no cameras, a volume that is empty
// or not finite, settings out of range.
[[nodiscard]] std::expected<CoverageReport, std::string> evaluate_coverage(const CameraRig& rig, const TrackingVolume& volume,
                                                                           const CoverageSettings& settings = {});

}  // namespace rhot
