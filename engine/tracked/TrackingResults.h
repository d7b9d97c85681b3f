#pragma once
// What tracking delivers to the engine each frame, whatever produced it (live cameras through
// the tracker, or a recording): the hands, the star-tracked objects, and for the debug views and
// the overlay the triangulated points and a few counts. The tracking system copies it into
// components (TrackedObjects.h); nothing else in the engine reads it.

#include <array>
#include <cstddef>
#include <limits>
#include <map>
#include <vector>

#include <Eigen/Core>

#include "engine/hand/HandComponents.h"
#include "tracking/core/Rigid3.h"

namespace rhot {

struct TrackingCounts {
  std::size_t detections = 0;                      // over all cameras
  std::vector<std::size_t> detections_per_camera;  // in rig order (empty without cameras)
  std::vector<int> cameras_without_frame;          // cameras whose frame never came (lost or late camera nodes)
  std::size_t points = 0;                          // triangulated
  double mean_reprojection_rms_px = 0.0;           // over the triangulated points
  int stars_seen = 0;                              // objects' stars measured this frame
  std::vector<int> seen_star_ids;
  std::array<bool, 2> hands_seen{};  // 0 left, 1 right: the tracker found the hand this frame
};

struct TrackingResults {
  double t_s = 0.0;
  // When the frame's images were exposed (steady clock, base/SteadyClock.h), where the source
  // knows; NaN otherwise (the runtime then counts from the start of the frame).
  double capture_steady_s = std::numeric_limits<double>::quiet_NaN();
  std::array<HandInput, 2> hands;  // 0 left, 1 right
  // Pinch and grip per hand, where a hand tracker measured them (not in a recording).
  std::array<HandGesture, 2> pinch{};
  std::array<HandGesture, 2> grip{};
  bool gestures_measured = false;
  // The objects measured this frame, by marker-star id: where each object is (its star's filtered
  // pose; finite poses only), and whether that pose is certain to within the star tracker's
  // report bounds (StarTracker.h: 10 mm and 5 degrees by default). An uncertain pose is the best
  // estimate there is; an application that must not act on a wrong one checks it (absent where
  // the source does not know: a replay).
  std::map<int, Rigid3d> world_from_object;
  std::map<int, bool> object_certain;
  std::vector<Eigen::Vector3d> points;          // triangulated markers, world
  std::vector<std::vector<int>> point_cameras;  // per point: the cameras that saw it
  std::vector<int> point_colours;               // per point: its marker colour (tracking/core/MarkerColour.h), -1 for none
  TrackingCounts counts;
};

}  // namespace rhot
