#include "tracking/plan/Coverage.h"
#include "tracking/core/Solvers.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include <Eigen/Cholesky>

namespace rhot {

namespace {

// sqrt of the chi-square distribution's 95th percentile with three degrees of freedom (7.815).
constexpr double kChi3Radius95 = 2.7955;

double quantile(std::vector<double>& values, double q) {
  if (values.empty()) return 0.0;
  const auto k =
      static_cast<std::size_t>(std::clamp(q * static_cast<double>(values.size() - 1), 0.0, static_cast<double>(values.size() - 1)));
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(k), values.end());
  return values[k];
}

}  // namespace

std::vector<int> cameras_seeing(std::span<const CameraProjection> cameras, const Eigen::Vector3d& p_world) {
  std::vector<int> out;
  for (std::size_t c = 0; c < cameras.size(); ++c) {
    const auto pixel = cameras[c].project(p_world);
    if (pixel && cameras[c].in_image(*pixel)) out.push_back(static_cast<int>(c));
  }
  return out;
}

std::optional<Eigen::Matrix3d> predicted_covariance(std::span<const CameraProjection> cameras, std::span<const int> seeing,
                                                    const Eigen::Vector3d& p_world, double sigma_px) {
  if (seeing.size() < 2) return std::nullopt;
  Eigen::Matrix3d fisher = Eigen::Matrix3d::Zero();
  Eigen::Matrix<double, 2, 3> j;
  for (const int c : seeing) {
    if (!cameras[static_cast<std::size_t>(c)].project(p_world, j)) return std::nullopt;
    fisher += j.transpose() * j;
  }
  fisher /= sigma_px * sigma_px;
  const SymmetricEigen3 solver = symmetric_eigen(fisher);
  if (!(solver.values(0) > 1e-12 * solver.values(2))) return std::nullopt;
  return solver.vectors * solver.values.cwiseInverse().asDiagonal() * solver.vectors.transpose();
}

std::expected<CoverageReport, std::string> evaluate_coverage(const CameraRig& rig, const TrackingVolume& volume,
                                                             const CoverageSettings& settings) {
  if (rig.cameras.empty()) return std::unexpected(std::string("the rig has no cameras"));
  if (!volume.size_m.allFinite() || !(volume.size_m.minCoeff() > 0.0)) {
    return std::unexpected(std::string("volume: every side must be positive and finite"));
  }
  if (!volume.centre_m.allFinite()) return std::unexpected(std::string("volume: its centre must be finite"));
  if (!(settings.sigma_px > 0.0) || !std::isfinite(settings.sigma_px)) return std::unexpected(std::string("sigma: must be positive"));
  if (!(settings.grid_step_m >= 0.0) || !std::isfinite(settings.grid_step_m)) {
    return std::unexpected(std::string("grid step: must be positive (or 0 for automatic)"));
  }
  if (settings.max_points < 1 || settings.samples_per_point < 1) {
    return std::unexpected(std::string("grid points and samples per point: at least 1"));
  }

  CoverageReport out;
  out.volume = volume;
  out.sigma_px = settings.sigma_px;
  CoverageGrid& g = out.grid;
  const double spacing = settings.grid_step_m > 0.0 ? settings.grid_step_m : std::cbrt(volume.size_m.prod() / settings.max_points);
  const Eigen::Vector3d cells = (volume.size_m / spacing).array().round().max(1.0);
  if (cells.prod() > 5e7) return std::unexpected(std::string("grid step: too fine for the volume (over 50 million points)"));
  g.nx = static_cast<int>(cells.x());
  g.ny = static_cast<int>(cells.y());
  g.nz = static_cast<int>(cells.z());
  g.step_m = Eigen::Vector3d(volume.size_m.x() / g.nx, volume.size_m.y() / g.ny, volume.size_m.z() / g.nz);
  g.origin_m = volume.centre_m - 0.5 * volume.size_m + 0.5 * g.step_m;

  const std::vector<CameraProjection> cameras = camera_projections(rig);
  out.views.assign(g.size(), 0);
  out.rms_error_mm.assign(g.size(), std::numeric_limits<double>::quiet_NaN());
  std::mt19937 rng(settings.seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::vector<double> errors_mm;
  std::size_t seen[4] = {0, 0, 0, 0};
  for (int y = 0; y < g.ny; ++y) {
    for (int z = 0; z < g.nz; ++z) {
      for (int x = 0; x < g.nx; ++x) {
        const Eigen::Vector3d p = g.point(x, y, z);
        const std::size_t i = g.index(x, y, z);
        const std::vector<int> seeing = cameras_seeing(cameras, p);
        out.views[i] = static_cast<int>(seeing.size());
        for (std::size_t k = 1; k <= 3; ++k) seen[k] += seeing.size() >= k ? 1 : 0;
        if (seeing.size() < 2) continue;
        const auto cov = predicted_covariance(cameras, seeing, p, settings.sigma_px);
        if (!cov) {
          // Rays parallel there: no depth at all.
          out.rms_error_mm[i] = std::numeric_limits<double>::infinity();
          for (int s = 0; s < settings.samples_per_point; ++s) errors_mm.push_back(std::numeric_limits<double>::infinity());
          out.predicted_max_mm = std::numeric_limits<double>::infinity();
          out.worst_point_m = p;
          continue;
        }
        const Eigen::Matrix3d cov_mm = *cov * 1e6;
        out.rms_error_mm[i] = std::sqrt(cov_mm.trace());
        const double worst = kChi3Radius95 * std::sqrt(symmetric_eigenvalues(cov_mm)(2));
        if (worst > out.predicted_max_mm) {
          out.predicted_max_mm = worst;
          out.worst_point_m = p;
        }
        const Eigen::Matrix3d l = cov_mm.llt().matrixL();
        for (int s = 0; s < settings.samples_per_point; ++s) {
          const Eigen::Vector3d n{normal(rng), normal(rng), normal(rng)};
          errors_mm.push_back((l * n).norm());
        }
      }
    }
  }
  const auto total = static_cast<double>(g.size());
  out.coverage_1 = static_cast<double>(seen[1]) / total;
  out.coverage_2 = static_cast<double>(seen[2]) / total;
  out.coverage_3 = static_cast<double>(seen[3]) / total;
  if (errors_mm.empty()) {
    // No point seen by two cameras: no error to predict anywhere.
    out.predicted_median_mm = out.predicted_p95_mm = out.predicted_max_mm = std::numeric_limits<double>::quiet_NaN();
    out.worst_point_m.setConstant(std::numeric_limits<double>::quiet_NaN());
    return out;
  }
  out.predicted_median_mm = quantile(errors_mm, 0.5);
  out.predicted_p95_mm = quantile(errors_mm, 0.95);
  return out;
}

}  // namespace rhot
