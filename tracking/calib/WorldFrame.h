#pragma once
// The world frame of a calibrated rig (metres, +Y up, -Z forward), set from an L-frame laid on
// the floor or from points touched on the floor.
//
// rhot's L-frame (docs/calibration.md): markers on two perpendicular arms lying on the floor.
// Marker 0 sits at the corner, the world's origin; marker 1 at the end of the long arm, which
// points along the world's -Z (forward); marker 2 at the end of the short arm, along +X (right);
// an optional fourth marker sits on the long arm, `middle_m` from the corner, making the frame
// harder to misread. Every marker's centre is `height_m` above the floor. The markers need no
// labels: the frame's edge lengths tell them apart.
//
// Floor points: a single marker held still at three or more places on the floor, one after the
// other. The first place is the origin, the second lies along +X; +Y is the floor's normal on the
// side of the cameras.

#include <expected>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "tracking/calib/Detections.h"
#include "tracking/calib/Similarity.h"
#include "tracking/camera/Camera.h"

namespace rhot {

struct LFrame {
  double long_m = 0.5;
  double short_m = 0.3;
  std::optional<double> middle_m;  // the fourth marker on the long arm, if the frame has one
  double height_m = 0.0;           // of the markers' centres above the floor

  // Its markers where they lie in the world they define (marker 0 the corner, 1 the long end,
  // 2 the short end, 3 the middle marker).
  std::vector<Eigen::Vector3d> markers_world() const;
  [[nodiscard]] std::expected<void, std::string> check() const;
};

// A marker that stayed in one place over several frames, found by matching and triangulating
// every frame (tracking/geometry) and grouping the points within `radius_m` of each other in frames
// at most 10 apart. Only a group's points within 5 mm of its median count, and it needs
// `min_frames` of them: a marker moving, even slowly, leaves too few; groups at one place are joined.
struct StillPoint {
  Eigen::Vector3d position{0, 0, 0};  // the median of its frames' points, in the rig's world
  int frames = 0;
  long first_frame = 0;
};
std::vector<StillPoint> still_points(const CameraRig& rig, const Detections& detections, double radius_m, int min_frames);

struct WorldFrameReport {
  std::vector<double> marker_residual_mm;  // per frame marker (or floor point): distance from its place
  double rms_mm = 0.0;
  double max_mm = 0.0;
  double angle_error_deg = 0.0;  // L-frame: measured angle between the arms minus 90; floor: the tilt the points' spread leaves uncertain
  double scale = 1.0;            // applied to the rig (1 unless rescaling was asked for)
  int frames = 0;                // frames the points were averaged over (the fewest of any point)
  std::vector<Eigen::Vector3d> measured_world;  // the frame's markers / floor points in the new world
};

struct WorldFrameResult {
  CameraRig rig;  // the same cameras in the new world
  Similarity3 new_from_old;
  WorldFrameReport report;
};

// From detections of the L-frame lying still. `rescale`: also scale the rig so that the frame's
// arms have their true lengths (for a rig calibrated without a wand). Fails when the markers
// found are not 3 (or 4, with a middle marker), or do not fit the frame within `tolerance_m`.
[[nodiscard]] std::expected<WorldFrameResult, std::string> world_from_lframe(const CameraRig& rig, const Detections& detections,
                                                                             const LFrame& frame, bool rescale, double tolerance_m = 0.01);

// From detections of one marker held still at three or more places on the floor (`marker_height_m`
// above it), each for at least `min_frames` frames.
[[nodiscard]] std::expected<WorldFrameResult, std::string> world_from_floor_points(const CameraRig& rig, const Detections& detections,
                                                                                   double marker_height_m, int min_frames = 10);

}  // namespace rhot
