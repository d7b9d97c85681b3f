#pragma once
// Extrinsics of 2 to 32 cameras from one marker, or a wand of two, waved through the volume.
//
// 1. The detections become point tracks (one marker in one frame, Detections.h) and every pixel
//    is undistorted with its own camera's intrinsics before any geometry.
// 2. A camera graph: an edge where two cameras saw at least `min_shared_points` tracks together.
//    A graph in pieces is an error naming the cameras that cannot be connected.
// 3. Initialisation over the graph, not a chain: the best-connected pair's relative pose from its
//    essential matrix (RANSAC), its tracks triangulated; then, one at a time, the camera seeing
//    the most reconstructed points is placed against all of them (PnP with RANSAC), new tracks
//    are triangulated, and everything placed so far is bundle-adjusted.
// 4. Bundle adjustment of all cameras and points with a robust loss, optionally refining focal
//    length, principal point and k1 per camera; observations far off (by default 5 robust sigmas,
//    at least 1 px) are dropped, and the adjustment repeated.
// 5. Scale: with a wand, markers A and B are `wand_length_m` apart; the scale minimising the
//    squared length errors over every frame that saw both ends. Without one the unit is the
//    distance between the first two cameras placed, and the report says the rig is not metric.
// 6. The frame: until `world` sets one (WorldFrame.h), the world is camera 0's, turned into rhot's
//    axes (X right, Y up, -Z along camera 0's view).

#include <expected>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "tracking/calib/CalibPictures.h"
#include "tracking/calib/Detections.h"
#include "tracking/camera/Camera.h"

namespace rhot {

struct WandSettings {
  std::optional<double> wand_length_m;  // the distance between markers A and B; nothing: no scale
  int marker_a = 0;
  int marker_b = 1;
  bool refine_focal = false;
  bool refine_principal_point = false;
  bool refine_k1 = false;
  // The intrinsics are rough guesses (no intrinsic calibration): try focal lengths from 0.5 to 2
  // image widths and keep the one that explains the detections best. Implies refine_focal.
  bool search_focal = false;
  double outlier_px = 0.0;  // observations further off are dropped; 0: 5 robust sigmas, at least 1 px
  // How far off a detection may be from the starting intrinsics' model while the cameras are
  // placed (essential matrix, PnP); 0: 3 px, or 10 px when intrinsics are to be refined.
  double initial_tolerance_px = 0.0;
  int min_shared_points = 15;  // points two cameras must share for an edge of the camera graph
  int min_points = 30;         // points a camera must see
  int threads = 2;

  [[nodiscard]] std::expected<void, std::string> check() const;
};

struct CameraCalibrationReport {
  std::string name;
  double rms_px = 0.0;  // over the inliers
  double median_px = 0.0;
  double p95_px = 0.0;
  int inliers = 0;
  int outliers = 0;
  int frames_seen = 0;    // frames in which the camera saw at least one inlier
  double coverage = 0.0;  // of the image, by a 16 x 16 grid (CalibPictures.h)
};

struct GraphEdge {
  int a = 0, b = 0;
  int shared_points = 0;
};

struct WandReport {
  double rms_px = 0.0;
  std::vector<CameraCalibrationReport> cameras;
  std::vector<GraphEdge> graph;  // every pair that shares a point
  std::vector<int> placement_order;
  int points = 0;             // 3D points (tracks) in the final adjustment
  int outliers = 0;           // observations dropped as outliers
  int ambiguous = 0;          // observations dropped before: several unlabelled blobs in one camera
  bool metric = false;        // scaled by a wand
  int wand_frames = 0;        // frames with both wand ends reconstructed
  double wand_mean_mm = 0.0;  // signed mean of (measured - true) length
  double wand_rms_mm = 0.0;
  double wand_max_mm = 0.0;        // largest absolute error
  double focal_searched_px = 0.0;  // the focal length the search chose (search_focal only)
  int iterations = 0;              // of the final bundle adjustment
  std::vector<std::string> warnings;
};

struct WandCalibration {
  CameraRig rig;
  WandReport report;
  std::vector<Eigen::Vector3d> points_world;           // every reconstructed point, in the rig's world
  std::vector<std::vector<ResidualSample>> residuals;  // per camera, for pictures
};

// `intrinsics`: the cameras (names, image sizes, intrinsics) in detection order; their poses are
// ignored. Fails with one message for bad input (a detection outside its camera's image, a camera
// index the rig lacks, too few points, a graph in pieces, a planar or tiny wave, cameras that look
// swapped) or a calibration that does not converge. `progress` receives a line per step.
[[nodiscard]] std::expected<WandCalibration, std::string> calibrate_wand(const CameraRig& intrinsics, const Detections& detections,
                                                                         const WandSettings& settings,
                                                                         const std::function<void(const std::string&)>& progress = {});

}  // namespace rhot
