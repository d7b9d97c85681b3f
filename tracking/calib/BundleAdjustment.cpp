#include "tracking/calib/BundleAdjustment.h"

#include <cmath>
#include <limits>

#include <ceres/ceres.h>
#include <ceres/rotation.h>
#include <Eigen/Geometry>

namespace rhot {

namespace {

// Per camera: pose (angle-axis rotation and translation, cam_from_world) and intrinsics
// (f = fx, cx, cy, k1); fy = f * aspect, and k2, p1, p2, k3 are constants.
struct CameraBlock {
  double pose[6];
  double intrinsics[4];
};

struct ReprojectionError {
  ReprojectionError(const Eigen::Vector2d& pixel, const CameraIntrinsics& k)
      : u(pixel.x()),
        v(pixel.y()),
        aspect(k.fy / k.fx),
        k2(k.distortion[1]),
        p1(k.distortion[2]),
        p2(k.distortion[3]),
        k3(k.distortion[4]) {}

  template <typename T>
  bool operator()(const T* pose, const T* intrinsics, const T* point, T* residual) const {
    T p[3];
    ceres::AngleAxisRotatePoint(pose, point, p);
    p[0] += pose[3];
    p[1] += pose[4];
    p[2] += pose[5];
    const T x = p[0] / p[2];
    const T y = p[1] / p[2];
    const T r2 = x * x + y * y;
    const T radial = T(1) + intrinsics[3] * r2 + T(k2) * r2 * r2 + T(k3) * r2 * r2 * r2;
    const T xd = x * radial + T(2 * p1) * x * y + T(p2) * (r2 + T(2) * x * x);
    const T yd = y * radial + T(p1) * (r2 + T(2) * y * y) + T(2 * p2) * x * y;
    residual[0] = intrinsics[0] * xd + intrinsics[1] - T(u);
    residual[1] = intrinsics[0] * T(aspect) * yd + intrinsics[2] - T(v);
    return true;
  }

  double u, v, aspect, k2, p1, p2, k3;
};

// A weak prior on camera 1's distance from camera 0 (whose pose is held): the scale is a gauge
// freedom of the reprojection error, and this residual makes the normal equations regular without
// pulling on anything the pixels decide. Weight: a 1 % change of the distance costs as much as a
// 1 px residual.
struct ScalePrior {
  double distance;
  Eigen::Vector3d c0;
  template <typename T>
  bool operator()(const T* pose, T* residual) const {
    // centre = -R^T t: rotate -t by the inverse rotation.
    const T minus_r[3] = {-pose[0], -pose[1], -pose[2]};
    const T minus_t[3] = {-pose[3], -pose[4], -pose[5]};
    T centre[3];
    ceres::AngleAxisRotatePoint(minus_r, minus_t, centre);
    const T dx = centre[0] - T(c0.x()), dy = centre[1] - T(c0.y()), dz = centre[2] - T(c0.z());
    residual[0] = (ceres::sqrt(dx * dx + dy * dy + dz * dz) - T(distance)) / T(0.01 * distance);
    return true;
  }
};

CameraBlock to_block(const Camera& c) {
  CameraBlock b{};
  const Eigen::AngleAxisd aa(c.cam_from_world.rotation.normalized());
  const Eigen::Vector3d r = aa.axis() * aa.angle();
  for (int i = 0; i < 3; ++i) {
    b.pose[i] = r[i];
    b.pose[3 + i] = c.cam_from_world.translation[i];
  }
  b.intrinsics[0] = c.intrinsics.fx;
  b.intrinsics[1] = c.intrinsics.cx;
  b.intrinsics[2] = c.intrinsics.cy;
  b.intrinsics[3] = c.intrinsics.distortion[0];
  return b;
}

void from_block(const CameraBlock& b, Camera& c) {
  const Eigen::Vector3d r(b.pose[0], b.pose[1], b.pose[2]);
  const double angle = r.norm();
  c.cam_from_world.rotation = angle > 0 ? Eigen::Quaterniond(Eigen::AngleAxisd(angle, r / angle)) : Eigen::Quaterniond::Identity();
  c.cam_from_world.translation = Eigen::Vector3d(b.pose[3], b.pose[4], b.pose[5]);
  const double aspect = c.intrinsics.fy / c.intrinsics.fx;
  c.intrinsics.fx = b.intrinsics[0];
  c.intrinsics.fy = b.intrinsics[0] * aspect;
  c.intrinsics.cx = b.intrinsics[1];
  c.intrinsics.cy = b.intrinsics[2];
  c.intrinsics.distortion[0] = b.intrinsics[3];
}

double rms(const std::vector<Eigen::Vector2d>& residuals) {
  double sum = 0;
  std::size_t n = 0;
  for (const Eigen::Vector2d& r : residuals) {
    if (!r.allFinite()) continue;
    sum += r.squaredNorm();
    ++n;
  }
  return n > 0 ? std::sqrt(sum / static_cast<double>(n)) : 0.0;
}

bool held(const BundleSettings& s, int camera) {
  for (const int c : s.held_cameras) {
    if (c == camera) return true;
  }
  return false;
}

}  // namespace

std::vector<Eigen::Vector2d> reprojection_residuals(const std::vector<Camera>& cameras, const std::vector<Eigen::Vector3d>& points,
                                                    const std::vector<BundleObservation>& observations) {
  std::vector<Eigen::Vector2d> out;
  out.reserve(observations.size());
  for (const BundleObservation& o : observations) {
    const auto p = cameras[static_cast<std::size_t>(o.camera)].project(points[static_cast<std::size_t>(o.point)]);
    out.push_back(p ? Eigen::Vector2d(o.pixel - *p) : Eigen::Vector2d::Constant(std::numeric_limits<double>::quiet_NaN()));
  }
  return out;
}

std::expected<BundleSummary, std::string> bundle_adjust(std::vector<Camera>& cameras, std::vector<Eigen::Vector3d>& points,
                                                        const std::vector<BundleObservation>& observations,
                                                        const BundleSettings& settings) {
  const int n_cameras = static_cast<int>(cameras.size());
  const int n_points = static_cast<int>(points.size());
  for (const BundleObservation& o : observations) {
    if (o.camera < 0 || o.camera >= n_cameras || o.point < 0 || o.point >= n_points) {
      return std::unexpected("bundle adjustment: an observation refers to camera " + std::to_string(o.camera) + " / point " +
                             std::to_string(o.point) + ", which do not exist");
    }
    if (!o.pixel.allFinite()) return std::unexpected("bundle adjustment: an observation's pixel is not finite");
  }
  for (const Camera& c : cameras) {
    if (!c.cam_from_world.is_finite()) return std::unexpected("bundle adjustment: camera " + c.name + " starts from a non-finite pose");
  }
  for (const Eigen::Vector3d& p : points) {
    if (!p.allFinite()) return std::unexpected("bundle adjustment: a point starts from a non-finite position");
  }
  BundleSummary summary;
  summary.initial_rms_px = rms(reprojection_residuals(cameras, points, observations));

  std::vector<CameraBlock> blocks;
  blocks.reserve(cameras.size());
  for (const Camera& c : cameras) blocks.push_back(to_block(c));
  std::vector<Eigen::Vector3d> solved = points;

  ceres::Problem::Options problem_options;
  problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  ceres::HuberLoss loss(settings.huber_px);
  std::vector<bool> used(cameras.size(), false);
  for (const BundleObservation& o : observations) {
    auto* cost = new ceres::AutoDiffCostFunction<ReprojectionError, 2, 6, 4, 3>(
        new ReprojectionError(o.pixel, cameras[static_cast<std::size_t>(o.camera)].intrinsics));
    CameraBlock& b = blocks[static_cast<std::size_t>(o.camera)];
    problem.AddResidualBlock(cost, &loss, b.pose, b.intrinsics, solved[static_cast<std::size_t>(o.point)].data());
    used[static_cast<std::size_t>(o.camera)] = true;
  }
  for (int c = 0; c < n_cameras; ++c) {
    if (!used[static_cast<std::size_t>(c)]) continue;
    CameraBlock& b = blocks[static_cast<std::size_t>(c)];
    if (held(settings, c)) {
      problem.SetParameterBlockConstant(b.pose);
      problem.SetParameterBlockConstant(b.intrinsics);
      continue;
    }
    std::vector<int> constant;
    if (!settings.refine_focal) constant.push_back(0);
    if (!settings.refine_principal_point) {
      constant.push_back(1);
      constant.push_back(2);
    }
    if (!settings.refine_k1) constant.push_back(3);
    if (constant.size() == 4) {
      problem.SetParameterBlockConstant(b.intrinsics);
    } else if (!constant.empty()) {
      problem.SetManifold(b.intrinsics, new ceres::SubsetManifold(4, constant));
    }
    if (c == 0 && settings.hold_first_pose) problem.SetParameterBlockConstant(b.pose);
  }
  if (settings.hold_first_pose && n_cameras >= 2 && used[0] && used[1] && !held(settings, 1) && !held(settings, 0)) {
    const double distance = (cameras[1].centre_world() - cameras[0].centre_world()).norm();
    if (distance > 0) {
      problem.AddResidualBlock(new ceres::AutoDiffCostFunction<ScalePrior, 1, 6>(new ScalePrior{distance, cameras[0].centre_world()}),
                               nullptr, blocks[1].pose);
    }
  }

  ceres::Solver::Options options;
  options.linear_solver_type = ceres::DENSE_SCHUR;
  options.max_num_iterations = settings.max_iterations;
  options.num_threads = settings.threads;
  options.function_tolerance = 1e-10;
  options.parameter_tolerance = 1e-10;
  options.logging_type = ceres::SILENT;
  ceres::Solver::Summary ceres_summary;
  ceres::Solve(options, &problem, &ceres_summary);
  if (!ceres_summary.IsSolutionUsable()) {
    return std::unexpected("bundle adjustment failed: " + ceres_summary.message);
  }
  std::vector<Camera> refined = cameras;
  for (int c = 0; c < n_cameras; ++c) from_block(blocks[static_cast<std::size_t>(c)], refined[static_cast<std::size_t>(c)]);
  for (const Camera& c : refined) {
    if (!c.cam_from_world.is_finite() || !std::isfinite(c.intrinsics.fx) || !(c.intrinsics.fx > 0) || !std::isfinite(c.intrinsics.cx) ||
        !std::isfinite(c.intrinsics.cy) || !std::isfinite(c.intrinsics.distortion[0])) {
      return std::unexpected("bundle adjustment ran off to values that are not finite or a focal length that is not positive (camera " +
                             c.name + "); nothing was changed");
    }
  }
  for (const Eigen::Vector3d& p : solved) {
    if (!p.allFinite()) return std::unexpected("bundle adjustment ran off to a point that is not finite; nothing was changed");
  }
  cameras = std::move(refined);
  points = std::move(solved);
  summary.iterations = static_cast<int>(ceres_summary.iterations.size());
  summary.converged = ceres_summary.termination_type == ceres::CONVERGENCE;
  summary.final_rms_px = rms(reprojection_residuals(cameras, points, observations));
  return summary;
}

}  // namespace rhot
