#pragma once
// What a frame source delivers: per camera, the 2D marker detections of one exposure with its
// timestamp. Sources with ground truth (the simulated rig) also give each detection's true marker
// and every marker's true position, for evaluation only: the tracker never reads them.

#include <cstdint>
#include <limits>
#include <vector>

#include <Eigen/Core>

#include "tracking/core/Rigid3.h"

namespace rhot {

struct Detection {
  Eigen::Vector2d pixel{0, 0};  // distorted pixel coordinates, sub-pixel
  int truth_marker = -1;        // ground truth (simulation only), -1 when unknown
  float area_px = 0.0f;         // the blob's pixels above threshold (0: not measured)
  float intensity = 0.0f;       // its peak grey level, 0-255 (0: not measured)
  std::int8_t colour = -1;      // its marker colour (MarkerColour.h), -1 for none (an infrared blob)
  float confidence = 0.0f;      // how surely it is that colour, 0-1 (0: not measured)
};

struct CameraFrame {
  int camera = 0;                     // index into the rig
  double timestamp_s = 0.0;           // mid-exposure, on the source's clock
  std::vector<Detection> detections;  // in no particular order
  bool delivered = true;              // false: no frame came from this camera (a lost or late camera node)
};

struct RigFrame {
  std::uint64_t index = 0;
  double time_s = 0.0;
  // When its images were exposed on this process's steady clock (base/SteadyClock.h), where the
  // source knows (camera nodes, video devices); NaN where it does not (the simulation, files): the
  // runtime then counts from the moment the frame was asked for.
  double capture_steady_s = std::numeric_limits<double>::quiet_NaN();
  std::vector<CameraFrame> cameras;               // one per camera in the rig
  std::vector<Eigen::Vector3d> truth_position_m;  // per marker (simulation only)
  std::vector<int> truth_marker_body;             // per marker: its rigid body, -1 for a loose marker (simulation only)
  std::vector<Rigid3d> truth_world_from_body;     // per rigid body (simulation only)
};

}  // namespace rhot
