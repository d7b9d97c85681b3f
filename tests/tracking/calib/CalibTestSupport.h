#pragma once
// Shared by the calibration tests.

#include "tracking/camera/Camera.h"
#include "tracking/core/Rigid3.h"

namespace rhot::test {

// The rig as a user's intrinsics-only files give it: every camera's intrinsics, identity poses.
// Calibrations start from this, never from the true poses.
inline CameraRig without_poses(CameraRig rig) {
  for (Camera& c : rig.cameras) c.cam_from_world = Rigid3d::identity();
  return rig;
}

}  // namespace rhot::test
