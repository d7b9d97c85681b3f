#pragma once
// Bundle adjustment of a rig of cameras and the 3D points they saw, with Ceres: every
// observation's pixel error under OpenCV's distortion model, a robust (Huber) loss, and per
// camera optionally its focal length (aspect kept), principal point and k1.
//
// The gauge: the first camera's pose is held (or the cameras named in `held_cameras`). The scale
// is held only weakly: a prior on camera 1's distance from camera 0, which the pixels cannot see,
// keeps the normal equations regular. A stiff constraint there (tried first) slowed convergence
// badly, leaving 30 % more residual than the noise after 100 iterations. Callers scale the result
// themselves (the wand calibration from the wand's length) or hold two cameras (a merge).

#include <expected>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "tracking/camera/Camera.h"

namespace rhot {

struct BundleObservation {
  int camera = 0;
  int point = 0;
  Eigen::Vector2d pixel{0, 0};  // distorted pixel
};

struct BundleSettings {
  bool refine_focal = false;            // fx and fy together (their ratio held)
  bool refine_principal_point = false;  // cx, cy
  bool refine_k1 = false;               // the first radial distortion coefficient
  double huber_px = 1.0;                // where the loss turns from quadratic to linear
  int max_iterations = 100;
  int threads = 2;
  bool hold_first_pose = true;
  std::vector<int> held_cameras;  // cameras whose pose and intrinsics are not refined at all
};

struct BundleSummary {
  int iterations = 0;
  double initial_rms_px = 0.0;
  double final_rms_px = 0.0;
  bool converged = false;
};

// Refines `cameras` and `points` in place. Fails (leaving both as they were) when the problem is
// ill-posed (an observation of a camera or point that does not exist, a non-finite start) or the
// solution is not finite. Cost: about one dense 10n x 10n solve per iteration for n cameras, plus
// a 3x3 block per point.
[[nodiscard]] std::expected<BundleSummary, std::string> bundle_adjust(std::vector<Camera>& cameras, std::vector<Eigen::Vector3d>& points,
                                                                      const std::vector<BundleObservation>& observations,
                                                                      const BundleSettings& settings);

// Observed minus predicted pixel of each observation (NaN where the point is behind the camera).
std::vector<Eigen::Vector2d> reprojection_residuals(const std::vector<Camera>& cameras, const std::vector<Eigen::Vector3d>& points,
                                                    const std::vector<BundleObservation>& observations);

}  // namespace rhot
