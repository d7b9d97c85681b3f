#pragma once
// Two rigs calibrated apart (for rooms where no single wave reaches every camera) joined into
// one through the cameras they share (the same name in both): Horn's closed-form similarity from
// the shared cameras' centres (scale too, with two shared cameras or more) and their
// orientations, then the shared cameras' two poses averaged. Rigs that share no camera are joined
// through shared points instead: the marker positions of one wave both saw (the same frame
// numbers in both sessions' detections), each triangulated by its own rig, aligned by the
// closed-form similarity. With both sessions' detections, one
// bundle adjustment over all of them follows (BundleAdjustment.h), every observation triangulated
// with the merged rig first.

#include <expected>
#include <optional>
#include <string>
#include <vector>

#include "tracking/calib/Detections.h"
#include "tracking/calib/Similarity.h"
#include "tracking/camera/Camera.h"

namespace rhot {

struct MergeSettings {
  bool allow_scale = true;  // with two shared cameras or more; else both rigs are taken as metric
};

struct MergeReport {
  std::vector<std::string> shared_cameras;
  int shared_points = 0;      // with no shared camera: marker positions both rigs reconstructed
  double point_rms_mm = 0.0;  // those points after the alignment, A against B
  Similarity3 a_from_b;
  double centre_rms_mm = 0.0;     // the shared cameras' centres after the alignment, A against B
  double rotation_rms_deg = 0.0;  // their orientations likewise
  bool adjusted = false;          // a bundle adjustment over both sessions ran
  double rms_px = 0.0;            // its reprojection RMS (adjusted only)
  int points = 0;
};

struct MergeResult {
  CameraRig rig;  // A's cameras, then B's that A lacks, in A's world
  MergeReport report;
};

// `detections_a`/`detections_b`: each session's detections, camera indices into its own rig; both
// or neither. Fails when the rigs share neither a camera nor (with detections) 10 points, or their
// shared cameras' intrinsics differ.
[[nodiscard]] std::expected<MergeResult, std::string> merge_rigs(const CameraRig& a, const CameraRig& b, const MergeSettings& settings,
                                                                 const Detections* detections_a = nullptr,
                                                                 const Detections* detections_b = nullptr);

}  // namespace rhot
